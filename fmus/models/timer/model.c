/* One-shot timer on integer nanoseconds.

   The period and every communication point are rounded to whole nanoseconds
   once (fixed_time.h) and compared as integers, never accumulated as doubles:
   summing h = 0.1 eight times gives 0.7999999999999999, which would fire a
   0.8 s timer one step late. With integers, a period of n steps fires on step n. */
#include "model.h"

static Status step(Instance *inst, double t, double h)
{
    ModelVariables *v = &inst->var;
    ModelState *s = &inst->state;
    int64_t now, end, period;

    if (!fixed_time_from_seconds(t, &now) || !fixed_time_from_seconds(t + h, &end)
        || !fixed_time_from_seconds(v->period, &period)) {
        return log_error(inst, "timer: t = %g, h = %g or period = %g is beyond the %g s the timer can count", t, h,
                         v->period, fixed_time_to_seconds(FIXED_TIME_LIMIT_NS));
    }
    if (v->start && !s->start_before) {
        s->armed = true;
        s->deadline_ns = now + period;
        log_event(inst, "timer started at t = %g s, fires at t = %g s", t, fixed_time_to_seconds(s->deadline_ns));
    }
    s->start_before = v->start;
    v->elapsed = s->armed && end >= s->deadline_ns;
    if (v->elapsed) {
        s->armed = false;
        log_event(inst, "timer elapsed at t = %g s", t + h);
    }
    v->remaining = s->armed ? fixed_time_to_seconds(s->deadline_ns - end) : 0.0;
    return STATUS_OK;
}

const ModelHooks MODEL_HOOKS = {.initialize = NULL, .step = step};
