/* Typed, checked access to model variables by value reference. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "owned_string.h"
#include "variables.h"

#if FMI_MAJOR_VERSION == 2
static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};
#elif FMI_MAJOR_VERSION == 3
static const char *const TYPE_NAMES[] = {"Float64", "Int32", "Boolean", "String"};
#else
#error "compile with -DFMI_MAJOR_VERSION=2 or 3"
#endif

static const char *const CAUSALITY_NAMES[] = {"independent variable", "parameter", "input", "output", "local"};

/* The generator guarantees that the member at info->offset has the C type of info->type. */
static void *field(Instance *inst, const VariableInfo *info)
{
    return (unsigned char *)&inst->var + info->offset;
}

static const VariableInfo *lookup(Instance *inst, const char *fn, unsigned int vr, VarType type)
{
    const VariableInfo *info;

    if (vr >= VARIABLE_COUNT) {
        log_error(inst, "%s: unknown value reference %u (this model has 0 to %u)", fn, vr, VARIABLE_COUNT - 1u);
        return NULL;
    }
    info = &MODEL_VARIABLES[vr];
    if (info->type != type) {
        log_error(inst, "%s: value reference %u is the %s variable '%s', not %s", fn, vr, TYPE_NAMES[info->type],
                  info->name, TYPE_NAMES[type]);
        return NULL;
    }
    return info;
}

/* The set rules of FMI 2 and 3 for co-simulation: inputs and tunable parameters
   at any time before termination, other variables with a start value only
   until initialization is done. */
static const VariableInfo *lookup_settable(Instance *inst, const char *fn, unsigned int vr, VarType type)
{
    const VariableInfo *info = lookup(inst, fn, vr, type);
    bool before_step = (inst->phase & (PHASE_INSTANTIATED | PHASE_INITIALIZATION)) != 0;

    if (info == NULL || info->causality == CAUSALITY_INPUT
        || (info->causality == CAUSALITY_PARAMETER && info->variability == VARIABILITY_TUNABLE)
        || (before_step && info->has_start && info->causality != CAUSALITY_INDEPENDENT)) {
        return info;
    }
    log_error(inst, "%s: %s%s '%s' (value reference %u) cannot be set %s", fn,
              info->causality == CAUSALITY_PARAMETER ? "fixed " : "", CAUSALITY_NAMES[info->causality], info->name,
              vr, before_step ? "(it has no start value)" : "after initialization");
    return NULL;
}

static Status check_range(Instance *inst, const char *fn, unsigned int vr, const VariableInfo *info, double value)
{
    if (!isfinite(value)) {
        /* Plant logic has no use for NaN or infinity; refusing them here keeps
           them from spreading silently through the model. */
        return log_error(inst, "%s: '%s' (value reference %u) cannot be %g", fn, info->name, vr, value);
    }
    if (info->has_min && value < info->min) {
        return log_error(inst, "%s: '%s' (value reference %u) = %.17g is below its minimum %.17g", fn, info->name,
                         vr, value, info->min);
    }
    if (info->has_max && value > info->max) {
        return log_error(inst, "%s: '%s' (value reference %u) = %.17g is above its maximum %.17g", fn, info->name,
                         vr, value, info->max);
    }
    return STATUS_OK;
}

void variables_free(Instance *inst)
{
    unsigned int vr;

    for (vr = 0; vr < VARIABLE_COUNT; vr++) {
        if (MODEL_VARIABLES[vr].type == VAR_STRING) {
            char **slot = field(inst, &MODEL_VARIABLES[vr]);
            free(*slot);
            *slot = NULL;
        }
    }
}

Status variables_reset(Instance *inst)
{
    unsigned int vr;

    variables_free(inst);
    inst->var = (ModelVariables){0};
    inst->state = (ModelState){0};
    for (vr = 0; vr < VARIABLE_COUNT; vr++) {
        const VariableInfo *info = &MODEL_VARIABLES[vr];
        void *value = field(inst, info);

        if (info->causality == CAUSALITY_INDEPENDENT) {
            continue;
        }
        switch (info->type) {
        case VAR_REAL: *(double *)value = info->has_start ? info->start.real : 0.0; break;
        case VAR_INT: *(int32_t *)value = info->has_start ? info->start.integer : 0; break;
        case VAR_BOOL: *(bool *)value = info->has_start && info->start.boolean; break;
        case VAR_STRING:
            /* Never NULL, so importers always get a valid C string. */
            if (variable_store_string(inst, vr, info->has_start ? info->start.string : "") != STATUS_OK) {
                return STATUS_ERROR;
            }
            break;
        }
    }
    return STATUS_OK;
}

Status variables_begin(Instance *inst, const char *fn, bool set, size_t n, const void *vrs, const void *values)
{
    unsigned allowed = set ? PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP
                           : PHASE_INITIALIZATION | PHASE_STEP | PHASE_TERMINATED | PHASE_ERROR;

    if (!instance_allows(inst, fn, allowed)) {
        return STATUS_ERROR;
    }
    if (n > 0 && (vrs == NULL || values == NULL)) {
        return log_error(inst, "%s: %zu values announced but an array is NULL", fn, n);
    }
    if (!set && n > 0 && inst->phase == PHASE_INITIALIZATION) {
        return instance_update_initial_unknowns(inst, fn);
    }
    return STATUS_OK;
}

Status variable_get_real(Instance *inst, const char *fn, unsigned int vr, double *value)
{
    const VariableInfo *info = lookup(inst, fn, vr, VAR_REAL);

    if (info == NULL) {
        return STATUS_ERROR;
    }
    *value = info->causality == CAUSALITY_INDEPENDENT ? inst->time : *(const double *)field(inst, info);
    return STATUS_OK;
}

Status variable_get_int(Instance *inst, const char *fn, unsigned int vr, int32_t *value)
{
    const VariableInfo *info = lookup(inst, fn, vr, VAR_INT);

    if (info == NULL) {
        return STATUS_ERROR;
    }
    *value = *(const int32_t *)field(inst, info);
    return STATUS_OK;
}

Status variable_get_bool(Instance *inst, const char *fn, unsigned int vr, bool *value)
{
    const VariableInfo *info = lookup(inst, fn, vr, VAR_BOOL);

    if (info == NULL) {
        return STATUS_ERROR;
    }
    *value = *(const bool *)field(inst, info);
    return STATUS_OK;
}

Status variable_get_string(Instance *inst, const char *fn, unsigned int vr, const char **value)
{
    const VariableInfo *info = lookup(inst, fn, vr, VAR_STRING);

    if (info == NULL) {
        return STATUS_ERROR;
    }
    *value = *(char *const *)field(inst, info);
    return STATUS_OK;
}

Status variable_set_real(Instance *inst, const char *fn, unsigned int vr, double value)
{
    const VariableInfo *info = lookup_settable(inst, fn, vr, VAR_REAL);

    if (info == NULL || check_range(inst, fn, vr, info, value) != STATUS_OK) {
        return STATUS_ERROR;
    }
    *(double *)field(inst, info) = value;
    return STATUS_OK;
}

Status variable_set_int(Instance *inst, const char *fn, unsigned int vr, int32_t value)
{
    const VariableInfo *info = lookup_settable(inst, fn, vr, VAR_INT);

    if (info == NULL || check_range(inst, fn, vr, info, value) != STATUS_OK) {
        return STATUS_ERROR;
    }
    *(int32_t *)field(inst, info) = value;
    return STATUS_OK;
}

Status variable_set_bool(Instance *inst, const char *fn, unsigned int vr, bool value)
{
    const VariableInfo *info = lookup_settable(inst, fn, vr, VAR_BOOL);

    if (info == NULL) {
        return STATUS_ERROR;
    }
    *(bool *)field(inst, info) = value;
    return STATUS_OK;
}

Status variable_set_string(Instance *inst, const char *fn, unsigned int vr, const char *value)
{
    const VariableInfo *info = lookup_settable(inst, fn, vr, VAR_STRING);

    if (info == NULL) {
        return STATUS_ERROR;
    }
    if (value == NULL) {
        return log_error(inst, "%s: '%s' (value reference %u) cannot be set to NULL", fn, info->name, vr);
    }
    return variable_store_string(inst, vr, value);
}

Status variable_store_string(Instance *inst, unsigned int vr, const char *value)
{
    char **slot;
    char *copy;

    if (vr >= VARIABLE_COUNT || MODEL_VARIABLES[vr].type != VAR_STRING) {
        return log_error(inst, "variable_store_string: value reference %u is not a string variable", vr);
    }
    /* Copy before freeing: value may be the current string itself. */
    copy = owned_string_copy(value);
    if (copy == NULL) {
        return log_error(inst, "out of memory copying a string of %zu bytes into '%s'", strlen(value),
                         MODEL_VARIABLES[vr].name);
    }
    slot = field(inst, &MODEL_VARIABLES[vr]);
    free(*slot);
    *slot = copy;
    return STATUS_OK;
}

Status variable_reject_type(Instance *inst, const char *fn, unsigned int vr, const char *type_name)
{
    if (vr >= VARIABLE_COUNT) {
        return log_error(inst, "%s: unknown value reference %u (this model has 0 to %u)", fn, vr,
                         VARIABLE_COUNT - 1u);
    }
    return log_error(inst, "%s: value reference %u is the %s variable '%s', not %s", fn, vr,
                     TYPE_NAMES[MODEL_VARIABLES[vr].type], MODEL_VARIABLES[vr].name, type_name);
}
