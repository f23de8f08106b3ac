/* Stiff first-order lag y' = (u - y) / tau, integrated inside doStep, as an
   exporting tool's FMU with its own fixed-step solver does.

   Each doStep(t, h) takes n = ceil(h / internal_step) equal explicit Euler
   steps dt = h / n, so a step of any length (the importer's 100 ms, or one
   physics tick of 6.67 ms) ends exactly at t + h. One Euler step multiplies the
   gap u - y by (1 - dt / tau): it shrinks only while dt < 2 tau (stable), and
   without changing sign while dt <= tau (monotone: no overshoot). The default
   dt / tau = 0.1 is both; a 100 ms step is 1000 internal steps, after which the
   gap would be 0.9^1000 ~ 1e-46 of the input step: in doubles y stops a few ulps
   from u, where a * (u - y) falls below half an ulp of y.
   internal_step >= 2 tau is refused rather than left to diverge. h is counted in
   integer nanoseconds (fixed_time.h) so that 0.1 / 0.0001 gives 1000 steps, not
   1001 for a double a few ulps above 1000. */
#include <stdint.h>

#include "model.h"

static Status step(Instance *inst, double t, double h)
{
    ModelVariables *v = &inst->var;
    int64_t h_ns, step_ns, n;
    double a;

    if (!(v->internal_step < 2.0 * v->tau)) {
        return log_error(inst,
                         "stiff_lag: internal_step = %g s is not below 2 * tau = %g s: explicit Euler would diverge",
                         v->internal_step, 2.0 * v->tau);
    }
    if (!fixed_time_from_seconds(h, &h_ns) || !fixed_time_from_seconds(v->internal_step, &step_ns) || step_ns <= 0) {
        return log_error(inst, "stiff_lag: h = %g s or internal_step = %g s cannot be counted in nanoseconds", h,
                         v->internal_step);
    }
    n = (h_ns + step_ns - 1) / step_ns;
    if (n > INT32_MAX) {
        return log_error(inst, "stiff_lag: the step from t = %g s of h = %g s needs more than %d internal steps", t, h,
                         INT32_MAX);
    }
    a = n > 0 ? (h / (double)n) / v->tau : 0.0;
    for (int64_t i = 0; i < n; i++) {
        v->y += a * (v->u - v->y);
    }
    v->substeps = (int32_t)n;
    return STATUS_OK;
}

const ModelHooks MODEL_HOOKS = {.initialize = NULL, .step = step};
