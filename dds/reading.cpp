#include "dds/reading.hpp"

#include "dds/domain.hpp"
#include "dds/idl_types.hpp"

namespace stac::dds {
namespace {

template <bool Ros2>
const dds_topic_descriptor_t* descriptor(dds::Topic t) {
  using T = dds::IdlTypes<Ros2>;
  switch (t) {
    case dds::Topic::kTrackedObjects:
      return T::tracked_objects();
    case dds::Topic::kSegments:
      return T::segments();
    case dds::Topic::kEgoPose:
      return T::ego_pose();
    case dds::Topic::kHealth:
      return T::health();
    case dds::Topic::kPointCloud:
      return T::point_cloud();
  }
  return nullptr;
}

}  // namespace

rt::Result<std::unique_ptr<TopicReaders>> TopicReaders::create(const dds::PublisherConfig& c) {
  // Made already in this process (`stac demo --view`: the viewer's readers, then the demo's):
  // this participant joins it, and the first TopicReaders, which deletes it, must go last.
  auto made = dds::create_domain(c, dds::ExistingDomain::kJoin);
  if (!made) return rt::Unexpected<rt::Error>{made.error()};
  const dds_entity_t domain = *made;
  const dds_entity_t participant = dds_create_participant(c.domain_id, nullptr, nullptr);
  if (participant < 0) {
    if (domain > 0) dds_delete(domain);
    return dds::dds_error("creating a DDS participant", participant);
  }
  return std::unique_ptr<TopicReaders>(new TopicReaders(c, domain, participant));
}

TopicReaders::~TopicReaders() {
  dds_delete(participant_);
  if (domain_ > 0) dds_delete(domain_);
}

rt::Result<dds_entity_t> TopicReaders::add(dds::Topic t, int depth,
                                           std::function<void(dds_entity_t)> take) {
  const std::string name = topic_name(t);
  const dds_topic_descriptor_t* type =
      config_.ros2_names ? descriptor<true>(t) : descriptor<false>(t);
  const dds_entity_t topic = dds_create_topic(participant_, type, name.c_str(), nullptr, nullptr);
  if (topic < 0) return dds::dds_error("creating DDS topic " + name, topic);
  dds::QosPtr qos = dds::reader_qos(t);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  takers_.push_back(std::move(take));
  dds_listener_t* listener = dds_create_listener(&takers_.back());
  dds_lset_data_available(listener, [](dds_entity_t reader, void* taker) {
    (*static_cast<std::function<void(dds_entity_t)>*>(taker))(reader);
  });
  const dds_entity_t reader = dds_create_reader(participant_, topic, qos.get(), listener);
  dds_delete_listener(listener);
  if (reader < 0) return dds::dds_error("creating a DDS reader of " + name, reader);
  return reader;
}

std::uint32_t TopicReaders::matched(dds_entity_t reader) noexcept {
  dds_subscription_matched_status_t s{};
  return dds_get_subscription_matched_status(reader, &s) == 0 ? s.current_count : 0;
}

std::string TopicReaders::topic_name(dds::Topic t) const {
  return dds::topic_name(t, config_.topic_prefix, config_.ros2_names);
}

}  // namespace stac::dds
