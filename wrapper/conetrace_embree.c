/* C shim for Embree 3: real functions for what bindgen cannot bind (static inline helpers
 * and macro constants). Keep this file free of logic; Rust owns everything else. */
#include "conetrace_embree.h"

void conetrace_rtc_init_intersect_context(struct RTCIntersectContext* context)
{
  rtcInitIntersectContext(context);
}

unsigned int conetrace_rtc_invalid_geometry_id(void)
{
  return RTC_INVALID_GEOMETRY_ID;
}

unsigned int conetrace_rtc_max_instance_level_count(void)
{
  return RTC_MAX_INSTANCE_LEVEL_COUNT;
}
