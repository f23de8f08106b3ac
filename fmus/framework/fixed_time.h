/* Time as an integer count of nanoseconds, for models that count or compare time. */
#ifndef FIXED_TIME_H
#define FIXED_TIME_H

#include <stdbool.h>
#include <stdint.h>

#define NS_PER_SECOND INT64_C(1000000000)

/* |t| below 2^62 ns (about 146 years), so the sum of two converted times
   cannot overflow an int64_t. */
#define FIXED_TIME_LIMIT_NS (INT64_C(1) << 62)

/* Round seconds to the nearest nanosecond. False if not finite or beyond the limit. */
bool fixed_time_from_seconds(double seconds, int64_t *ns);

double fixed_time_to_seconds(int64_t ns);

#endif
