// The C types idlc generates from idl/stac.idl, in either naming mode, as one traits struct so
// code is written once for both (STYLE rule 6). IdlTypes<false>: stac_msgs::msg::TrackedObjects;
// IdlTypes<true>: the ROS 2 mode, stac_msgs::msg::dds_::TrackedObjects_ (docs/dds.md).
#pragma once

#include "stac.h"
#include "stac_ros2.h"

namespace stac::dds {

// Bounds of idl/stac.idl (a static_assert in publisher.cpp checks them against the C types).
inline constexpr unsigned kMaxObjects = 512;
inline constexpr unsigned kMaxClassifications = 9;  // up to 8 model classes and background
inline constexpr unsigned kMaxClassNameLength = 31;
inline constexpr unsigned kMaxFootprint = 8;
inline constexpr unsigned kMaxSegments = 2048;
inline constexpr unsigned kMaxStages = 12;
inline constexpr unsigned kMaxDrops = 32;
inline constexpr unsigned kMaxSensors = 4;
inline constexpr unsigned kMaxCloudPoints = 131072;

template <bool Ros2>
struct IdlTypes;

template <>
struct IdlTypes<false> {
  using TrackedObjects = stac_msgs_msg_TrackedObjects;
  using TrackedObject = stac_msgs_msg_TrackedObject;
  using ObjectClassification = stac_msgs_msg_ObjectClassification;
  using Point2 = stac_msgs_msg_Point2;
  using ScanSegments = stac_msgs_msg_ScanSegments;
  using Segment = stac_msgs_msg_Segment;
  using EgoPose = stac_msgs_msg_EgoPose;
  using Health = stac_msgs_msg_Health;
  using StageLatency = stac_msgs_msg_StageLatency;
  using DropCount = stac_msgs_msg_DropCount;
  using SensorStatus = stac_msgs_msg_SensorStatus;
  using LabeledPointCloud = stac_msgs_msg_LabeledPointCloud;
  using LabeledPoint = stac_msgs_msg_LabeledPoint;
  static const dds_topic_descriptor_t* tracked_objects() {
    return &stac_msgs_msg_TrackedObjects_desc;
  }
  static const dds_topic_descriptor_t* segments() { return &stac_msgs_msg_ScanSegments_desc; }
  static const dds_topic_descriptor_t* ego_pose() { return &stac_msgs_msg_EgoPose_desc; }
  static const dds_topic_descriptor_t* health() { return &stac_msgs_msg_Health_desc; }
  static const dds_topic_descriptor_t* point_cloud() {
    return &stac_msgs_msg_LabeledPointCloud_desc;
  }
};

template <>
struct IdlTypes<true> {
  using TrackedObjects = stac_msgs_msg_dds__TrackedObjects_;
  using TrackedObject = stac_msgs_msg_dds__TrackedObject_;
  using ObjectClassification = stac_msgs_msg_dds__ObjectClassification_;
  using Point2 = stac_msgs_msg_dds__Point2_;
  using ScanSegments = stac_msgs_msg_dds__ScanSegments_;
  using Segment = stac_msgs_msg_dds__Segment_;
  using EgoPose = stac_msgs_msg_dds__EgoPose_;
  using Health = stac_msgs_msg_dds__Health_;
  using StageLatency = stac_msgs_msg_dds__StageLatency_;
  using DropCount = stac_msgs_msg_dds__DropCount_;
  using SensorStatus = stac_msgs_msg_dds__SensorStatus_;
  using LabeledPointCloud = stac_msgs_msg_dds__LabeledPointCloud_;
  using LabeledPoint = stac_msgs_msg_dds__LabeledPoint_;
  static const dds_topic_descriptor_t* tracked_objects() {
    return &stac_msgs_msg_dds__TrackedObjects__desc;
  }
  static const dds_topic_descriptor_t* segments() { return &stac_msgs_msg_dds__ScanSegments__desc; }
  static const dds_topic_descriptor_t* ego_pose() { return &stac_msgs_msg_dds__EgoPose__desc; }
  static const dds_topic_descriptor_t* health() { return &stac_msgs_msg_dds__Health__desc; }
  static const dds_topic_descriptor_t* point_cloud() {
    return &stac_msgs_msg_dds__LabeledPointCloud__desc;
  }
};

}  // namespace stac::dds
