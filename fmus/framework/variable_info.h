/* Description of one model variable and of one field of the model's private state, as generate.py
   writes them into model_description.c. */
#ifndef VARIABLE_INFO_H
#define VARIABLE_INFO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum { VAR_REAL, VAR_INT, VAR_BOOL, VAR_STRING } VarType;

typedef enum {
    CAUSALITY_INDEPENDENT, /* time: kept by the framework, not in ModelVariables */
    CAUSALITY_PARAMETER,
    CAUSALITY_INPUT,
    CAUSALITY_OUTPUT,
    CAUSALITY_LOCAL
} Causality;

typedef enum {
    VARIABILITY_FIXED,
    VARIABILITY_TUNABLE,
    VARIABILITY_DISCRETE,
    VARIABILITY_CONTINUOUS
} Variability;

typedef union {
    double real;
    int32_t integer;
    bool boolean;
    const char *string;
} StartValue;

typedef struct {
    const char *name;
    VarType type;
    Causality causality;
    Variability variability;
    size_t offset; /* of the value in ModelVariables */
    bool has_start; /* false: initial="calculated", the initialize hook computes it */
    StartValue start;
    bool has_min;
    bool has_max;
    double min; /* int bounds too: every int32 is exact in a double */
    double max;
} VariableInfo;

/* The C types a ModelState field may have (model.yaml's state types). */
typedef enum { STATE_REAL, STATE_INT32, STATE_INT64, STATE_BOOL } StateType;

typedef struct {
    const char *name; /* NULL ends the table */
    StateType type;
    size_t offset; /* of the value in ModelState */
} StateFieldInfo;

#endif
