/* The one header bindgen reads: Embree 3's public API plus conetrace's C shim.
 *
 * The shim (conetrace_embree.c) exports, as real linkable symbols, what bindgen cannot
 * emit from Embree's headers: the `RTC_FORCEINLINE` context initialisers and the
 * `RTC_INVALID_GEOMETRY_ID` macro cast. */
#pragma once

#include <embree3/rtcore.h>

/* rtcInitIntersectContext, callable from Rust. */
void conetrace_rtc_init_intersect_context(struct RTCIntersectContext* context);

/* The value of the RTC_INVALID_GEOMETRY_ID macro as this Embree build defines it. */
unsigned int conetrace_rtc_invalid_geometry_id(void);

/* The value of RTC_MAX_INSTANCE_LEVEL_COUNT as this Embree build defines it. */
unsigned int conetrace_rtc_max_instance_level_count(void);
