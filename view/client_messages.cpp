#include "view/client_messages.hpp"

#include <limits>
#include <nlohmann/json.hpp>

#include "rt/formatted.hpp"

namespace stac::view {
ClientMessageEffect apply_client_message(const std::string& payload, std::size_t channels,
                                         Subscriptions& subscriptions) {
  ClientMessageEffect out;
  std::size_t more = 0;
  const auto error = [&](std::string message) {
    if (out.errors.size() < kMaxStatusesPerMessage)
      out.errors.push_back(std::move(message));
    else
      ++more;
  };
  const nlohmann::json j = nlohmann::json::parse(payload, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("op") || !j["op"].is_string()) {
    out.errors.emplace_back("not a JSON object with an \"op\"");
    return out;
  }
  const std::string op = j["op"].get<std::string>();
  if (op == "subscribe" && j.contains("subscriptions") && j["subscriptions"].is_array()) {
    for (const nlohmann::json& s : j["subscriptions"]) {
      if (!s.is_object() || !s.contains("id") || !s.contains("channelId") ||
          !s["id"].is_number_unsigned() || !s["channelId"].is_number_unsigned()) {
        error("a subscription needs an unsigned \"id\" and \"channelId\"");
        continue;
      }
      // Ids are 32-bit on the wire (a message's header); a larger one is refused, not cut.
      const auto wide_id = s["id"].get<std::uint64_t>();
      if (wide_id > std::numeric_limits<std::uint32_t>::max()) {
        error("subscription id " + std::to_string(wide_id) + " is over 2^32-1");
        continue;
      }
      const auto id = static_cast<std::uint32_t>(wide_id);
      const auto channel = s["channelId"].get<std::uint64_t>();
      if (channel == 0 || channel > channels) {
        error("no channel " + std::to_string(channel));
        continue;
      }
      if (subscriptions.count(id) != 0) {
        error("subscription id " + std::to_string(id) + " is in use");
        continue;
      }
      // One subscription per channel and client (as Foxglove's own server): a client holds at
      // most as many subscriptions as there are channels, and gets each message once.
      bool already = false;
      for (const auto& [other_id, other_channel] : subscriptions)
        already = already || other_channel == channel - 1;
      if (already) {
        error("already subscribed to channel " + std::to_string(channel));
        continue;
      }
      subscriptions[id] = static_cast<std::size_t>(channel - 1);
      out.subscriber_changes.emplace_back(static_cast<std::size_t>(channel - 1), +1);
    }
  } else if (op == "unsubscribe" && j.contains("subscriptionIds") &&
             j["subscriptionIds"].is_array()) {
    for (const nlohmann::json& id : j["subscriptionIds"]) {
      if (!id.is_number_unsigned() ||
          id.get<std::uint64_t>() > std::numeric_limits<std::uint32_t>::max())
        continue;
      auto s = subscriptions.find(id.get<std::uint32_t>());
      if (s == subscriptions.end()) continue;
      out.subscriber_changes.emplace_back(s->second, -1);
      subscriptions.erase(s);
    }
  } else {
    error("unsupported op '" + rt::echoed(op) + "' (stac view serves subscribe and unsubscribe)");
  }
  if (more > 0) out.errors.push_back("... and " + std::to_string(more) + " more refused");
  return out;
}

}  // namespace stac::view
