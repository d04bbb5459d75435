/* Prints the object ids and positions of STAC's tracked objects (topic stac/tracked_objects,
 * domain 0 unless given). Usage: stac_c_subscriber [COUNT [DOMAIN]]. Cyclone's configuration
 * comes from $CYCLONEDDS_URI (e.g. file://.../config/dds/loopback.xml). */
#include <stdio.h>
#include <stdlib.h>

#include "dds/dds.h"
#include "stac.h"

int main(int argc, char** argv) {
  const int count = argc > 1 ? atoi(argv[1]) : 10;
  const dds_domainid_t domain = argc > 2 ? (dds_domainid_t)atoi(argv[2]) : 0;
  const dds_entity_t participant = dds_create_participant(domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "dds_create_participant: %s\n", dds_strretcode(-participant));
    return 1;
  }
  const dds_entity_t topic = dds_create_topic(participant, &stac_msgs_msg_TrackedObjects_desc,
                                              "stac/tracked_objects", NULL, NULL);
  if (topic < 0) {
    fprintf(stderr, "dds_create_topic: %s\n", dds_strretcode(-topic));
    return 1;
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 16);
  const dds_entity_t reader = dds_create_reader(participant, topic, qos, NULL);
  dds_delete_qos(qos);
  if (reader < 0) {
    fprintf(stderr, "dds_create_reader: %s\n", dds_strretcode(-reader));
    return 1;
  }
  int received = 0;
  for (int polls = 0; received < count && polls < 3000; ++polls) { /* about 30 s */
    void* samples[1] = {NULL};
    dds_sample_info_t info;
    const dds_return_t n = dds_take(reader, samples, &info, 1, 1);
    if (n < 0) {
      fprintf(stderr, "dds_take: %s\n", dds_strretcode(-n));
      return 1;
    }
    if (n == 0) {
      dds_sleepfor(DDS_MSECS(10));
      continue;
    }
    if (info.valid_data) {
      const stac_msgs_msg_TrackedObjects* s = samples[0];
      printf("scan %llu: %u objects\n", (unsigned long long)s->scan_index, s->objects._length);
      for (uint32_t i = 0; i < s->objects._length; ++i) {
        const stac_msgs_msg_TrackedObject* o = &s->objects._buffer[i];
        /* The most probable class first: its name is the publisher's model's (or "unknown"). */
        const char* cls =
            o->classification._length > 0 ? o->classification._buffer[0].name : "unknown";
        printf("  id %llu at x=%.2f y=%.2f class %s\n", (unsigned long long)o->object_id,
               o->kinematics.position.x, o->kinematics.position.y, cls);
      }
      fflush(stdout);
      ++received;
    }
    dds_return_loan(reader, samples, n);
  }
  dds_delete(participant);
  if (received < count) {
    fprintf(stderr, "stac_c_subscriber: %d of %d samples before the timeout\n", received, count);
    return 1;
  }
  return 0;
}
