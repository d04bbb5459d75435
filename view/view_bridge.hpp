// STAC's DDS topics served to Foxglove (docs/view.md): a participant reading point_cloud,
// tracked_objects, ego_pose and health, and a FoxgloveServer with a channel for each, fed as the
// samples arrive (on Cyclone's receive thread; a message is built only while someone is
// subscribed to its channel). `stac view` runs one alone, `stac demo --view` beside the demo.
#pragma once

#include <memory>
#include <string>

#include "dds/publisher.hpp"
#include "rt/expected.hpp"
#include "view/foxglove_server.hpp"

namespace stac::view {

class ViewBridge {
 public:
  static rt::Result<std::unique_ptr<ViewBridge>> start(const dds::PublisherConfig& dds,
                                                       const ServerOptions& server);
  ~ViewBridge();  // the readers first (no callback after), then the server
  ViewBridge(const ViewBridge&) = delete;
  ViewBridge& operator=(const ViewBridge&) = delete;

  [[nodiscard]] std::string url() const;  // ws://address:port
  [[nodiscard]] bool any_subscribed() const noexcept;
  [[nodiscard]] ServerCounts counts() const;
  // What was served, one line per channel, for the end of a run.
  [[nodiscard]] std::string summary() const;

  struct State;

 private:
  explicit ViewBridge(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace stac::view
