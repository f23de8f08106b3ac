/* Time as an integer count of nanoseconds, for models that count or compare time.

   Communication points reach an FMU as doubles, e.g. 0.1 + 0.1 + 0.1 =
   0.30000000000000004. Rounding each one to the nearest nanosecond and doing
   all arithmetic on the integers removes the drift: a deadline that is a
   whole number of steps away is hit on exactly that step, however long the run. */
#include <math.h>

#include "fixed_time.h"

bool fixed_time_from_seconds(double seconds, int64_t *ns)
{
    double scaled = seconds * (double)NS_PER_SECOND;

    /* The comparison is false for NaN as well. */
    if (!(fabs(scaled) < (double)FIXED_TIME_LIMIT_NS)) {
        return false;
    }
    *ns = llround(scaled);
    return true;
}

double fixed_time_to_seconds(int64_t ns)
{
    /* One correctly rounded division: the nearest double to the exact time
       while |ns| < 2^53 (104 days). */
    return (double)ns / (double)NS_PER_SECOND;
}
