/* Typed, checked access to model variables by value reference. */
#ifndef VARIABLES_H
#define VARIABLES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "instance.h"
#include "status.h"

/* Free the owned strings, zero the variables and the model state, apply the start values. */
Status variables_reset(Instance *inst);
void variables_free(Instance *inst);

/* Checks shared by every get/set call before its per-element loop: the phase
   and the arrays. A get during initialization first computes the initial unknowns. */
Status variables_begin(Instance *inst, const char *fn, bool set, size_t n, const void *vrs, const void *values);

Status variable_get_real(Instance *inst, const char *fn, unsigned int vr, double *value);
Status variable_get_int(Instance *inst, const char *fn, unsigned int vr, int32_t *value);
Status variable_get_bool(Instance *inst, const char *fn, unsigned int vr, bool *value);
Status variable_get_string(Instance *inst, const char *fn, unsigned int vr, const char **value);

Status variable_set_real(Instance *inst, const char *fn, unsigned int vr, double value);
Status variable_set_int(Instance *inst, const char *fn, unsigned int vr, int32_t value);
Status variable_set_bool(Instance *inst, const char *fn, unsigned int vr, bool value);
Status variable_set_string(Instance *inst, const char *fn, unsigned int vr, const char *value);

/* For FMI types the framework has no variables of (FMI 3 Int8, Binary, ...):
   the error names what vr really is. */
Status variable_reject_type(Instance *inst, const char *fn, unsigned int vr, const char *type_name);

/* Replace a string variable without the importer's set rules, for models that
   compute string outputs. */
Status variable_store_string(Instance *inst, unsigned int vr, const char *value);

#endif
