/* FMU states: copies of an instance's whole state and their serialized form, for both FMI versions. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "owned_string.h"
#include "state.h"
#include "variables.h"

/* The serialized form, every number little-endian whatever the machine:

     magic "PHSTATE\0" | u32 format | u64 total size | identifier | token
     | u32 variables | u32 state fields | u32 phase | f64 start time | f64 time
     | each variable but time, in value-reference order | each state field, in order
     | u64 FNV-1a hash of everything before it

   A string is a u32 length and its bytes; a real is the bits of an IEEE 754
   double, a bool one byte 0 or 1. The identifier and token name the model and
   its interface; the counts catch a binary built from another model.c. */
static const unsigned char MAGIC[8] = {'P', 'H', 'S', 'T', 'A', 'T', 'E', '\0'};
#define FORMAT_VERSION 1u
#define HEADER_SIZE (sizeof MAGIC + 4u + 8u)
#define HASH_SIZE 8u
/* Names of another model are cut to this length in messages. */
#define SHOWN 100

/* Reals travel as their 64 bits; a platform whose double is not IEEE binary64 does not compile. */
typedef char double_is_64_bits[sizeof(double) == 8 && sizeof(uint64_t) == 8 ? 1 : -1];

typedef struct {
    const void *owner; /* &MODEL_VARIABLES of the binary that made it: states of other FMUs are refused */
    Phase phase;
    double start_time;
    double time;
    ModelVariables var; /* its strings are the state's own */
    ModelState state;
} Snapshot;

static const void *const OWNER = MODEL_VARIABLES;

/* ------------------------------------------------------------ copies */

static char **string_slot(ModelVariables *var, const VariableInfo *info)
{
    return (char **)((unsigned char *)var + info->offset);
}

static bool is_string(const VariableInfo *info)
{
    return info->type == VAR_STRING && info->causality != CAUSALITY_INDEPENDENT;
}

static void free_strings(ModelVariables *var)
{
    unsigned int vr;

    for (vr = 0; vr < VARIABLE_COUNT; vr++) {
        if (is_string(&MODEL_VARIABLES[vr])) {
            char **slot = string_slot(var, &MODEL_VARIABLES[vr]);
            free(*slot);
            *slot = NULL;
        }
    }
}

/* Without freeing: for copies whose strings are another's, and for fresh memory. */
static void null_strings(ModelVariables *var)
{
    unsigned int vr;

    for (vr = 0; vr < VARIABLE_COUNT; vr++) {
        if (is_string(&MODEL_VARIABLES[vr])) {
            *string_slot(var, &MODEL_VARIABLES[vr]) = NULL;
        }
    }
}

/* to is a copy of from whose strings are still from's: give it copies of its
   own. On failure to holds no string at all (every one NULL). */
static bool own_strings(ModelVariables *to, const ModelVariables *from)
{
    ModelVariables *source = (ModelVariables *)from; /* only read */
    bool ok = true;
    unsigned int vr;

    null_strings(to);
    for (vr = 0; ok && vr < VARIABLE_COUNT; vr++) {
        if (is_string(&MODEL_VARIABLES[vr])) {
            char *copy = owned_string_copy(*string_slot(source, &MODEL_VARIABLES[vr]));

            *string_slot(to, &MODEL_VARIABLES[vr]) = copy;
            ok = copy != NULL;
        }
    }
    if (!ok) {
        free_strings(to);
    }
    return ok;
}

static Snapshot *checked(Instance *inst, const char *fn, const void *state)
{
    if (state == NULL) {
        log_error(inst, "%s: the FMU state is NULL", fn);
        return NULL;
    }
    if (((const Snapshot *)state)->owner != OWNER) {
        log_error(inst, "%s: the FMU state was not made by this FMU (%s)", fn, MODEL_IDENTIFIER);
        return NULL;
    }
    return (Snapshot *)state;
}

/* *state becomes fresh: in place when it already is a state (its strings freed first). */
static void put(void **state, Snapshot *fresh)
{
    Snapshot *old = *state;

    if (old == NULL) {
        *state = fresh;
        return;
    }
    free_strings(&old->var);
    *old = *fresh;
    free(fresh);
}

Status state_get(Instance *inst, const char *fn, void **state)
{
    Snapshot *snapshot;

    /* The error state is what a failed call left: not a state to go back to. */
    if (!instance_allows(inst, fn, PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP | PHASE_TERMINATED)) {
        return STATUS_ERROR;
    }
    if (state == NULL) {
        return log_error(inst, "%s: the FMU state argument is NULL", fn);
    }
    if (*state != NULL && checked(inst, fn, *state) == NULL) {
        return STATUS_ERROR;
    }
    snapshot = calloc(1, sizeof *snapshot);
    if (snapshot == NULL) {
        return log_error(inst, "%s: out of memory allocating an FMU state", fn);
    }
    snapshot->owner = OWNER;
    snapshot->phase = inst->phase;
    snapshot->start_time = inst->start_time;
    snapshot->time = inst->time;
    snapshot->var = inst->var;
    snapshot->state = inst->state;
    if (!own_strings(&snapshot->var, &inst->var)) {
        free(snapshot);
        return log_error(inst, "%s: out of memory copying the string variables into an FMU state", fn);
    }
    put(state, snapshot);
    return STATUS_OK;
}

Status state_set(Instance *inst, const char *fn, const void *state)
{
    const Snapshot *snapshot = checked(inst, fn, state);
    ModelVariables var;

    if (snapshot == NULL) {
        return STATUS_ERROR;
    }
    /* Copy first, so that running out of memory leaves the instance as it was. */
    var = snapshot->var;
    if (!own_strings(&var, &snapshot->var)) {
        return log_error(inst, "%s: out of memory copying the string variables of the FMU state", fn);
    }
    variables_free(inst);
    inst->var = var;
    inst->state = snapshot->state;
    inst->phase = snapshot->phase;
    inst->start_time = snapshot->start_time;
    inst->time = snapshot->time;
    return STATUS_OK;
}

Status state_free(Instance *inst, const char *fn, void **state)
{
    Snapshot *snapshot;

    if (state == NULL || *state == NULL) {
        return STATUS_OK; /* FMI: freeing nothing is ignored */
    }
    snapshot = checked(inst, fn, *state);
    if (snapshot == NULL) {
        return STATUS_ERROR;
    }
    free_strings(&snapshot->var);
    free(snapshot);
    *state = NULL;
    return STATUS_OK;
}

/* ------------------------------------------------------------ writing */

/* With at == NULL it only counts, so that one function gives both the size and the bytes. */
typedef struct {
    unsigned char *at;
    size_t size;
} Writer;

static void put_bytes(Writer *w, const void *bytes, size_t n)
{
    if (w->at != NULL && n > 0) {
        memcpy(w->at + w->size, bytes, n);
    }
    w->size += n;
}

static void put_uint(Writer *w, uint64_t value, size_t n)
{
    unsigned char bytes[8];
    size_t i;

    for (i = 0; i < n; i++) {
        bytes[i] = (unsigned char)(value >> (8u * i));
    }
    put_bytes(w, bytes, n);
}

static void put_real(Writer *w, double value)
{
    uint64_t bits;

    memcpy(&bits, &value, sizeof bits);
    put_uint(w, bits, 8);
}

static void put_string(Writer *w, const char *text)
{
    size_t n = strlen(text);

    put_uint(w, n, 4);
    put_bytes(w, text, n);
}

static uint64_t fnv1a(const unsigned char *bytes, size_t n)
{
    uint64_t hash = 14695981039346656037u;
    size_t i;

    for (i = 0; i < n; i++) {
        hash = (hash ^ bytes[i]) * 1099511628211u;
    }
    return hash;
}

static unsigned int state_field_count(void)
{
    unsigned int n = 0;

    while (MODEL_STATE_FIELDS[n].name != NULL) {
        n++;
    }
    return n;
}

/* Everything but the hash; w->size is then the size without it. */
static void encode(Writer *w, const Snapshot *snapshot, uint64_t total)
{
    const unsigned char *var = (const unsigned char *)&snapshot->var;
    const unsigned char *own = (const unsigned char *)&snapshot->state;
    const StateFieldInfo *field;
    unsigned int vr;

    put_bytes(w, MAGIC, sizeof MAGIC);
    put_uint(w, FORMAT_VERSION, 4);
    put_uint(w, total, 8);
    put_string(w, MODEL_IDENTIFIER);
    put_string(w, MODEL_TOKEN);
    put_uint(w, VARIABLE_COUNT, 4);
    put_uint(w, state_field_count(), 4);
    put_uint(w, (uint64_t)snapshot->phase, 4);
    put_real(w, snapshot->start_time);
    put_real(w, snapshot->time);
    for (vr = 0; vr < VARIABLE_COUNT; vr++) {
        const VariableInfo *info = &MODEL_VARIABLES[vr];
        const unsigned char *at = var + info->offset;

        if (info->causality == CAUSALITY_INDEPENDENT) {
            continue;
        }
        switch (info->type) {
        case VAR_REAL: put_real(w, *(const double *)at); break;
        case VAR_INT: put_uint(w, (uint32_t) * (const int32_t *)at, 4); break;
        case VAR_BOOL: put_uint(w, *(const bool *)at ? 1u : 0u, 1); break;
        case VAR_STRING: put_string(w, *(char *const *)at); break;
        }
    }
    for (field = MODEL_STATE_FIELDS; field->name != NULL; field++) {
        const unsigned char *at = own + field->offset;

        switch (field->type) {
        case STATE_REAL: put_real(w, *(const double *)at); break;
        case STATE_INT32: put_uint(w, (uint32_t) * (const int32_t *)at, 4); break;
        case STATE_INT64: put_uint(w, (uint64_t) * (const int64_t *)at, 8); break;
        case STATE_BOOL: put_uint(w, *(const bool *)at ? 1u : 0u, 1); break;
        }
    }
}

static size_t serialized_size(const Snapshot *snapshot)
{
    Writer counter = {NULL, 0};

    encode(&counter, snapshot, 0);
    return counter.size + HASH_SIZE;
}

Status state_serialized_size(Instance *inst, const char *fn, const void *state, size_t *size)
{
    const Snapshot *snapshot = checked(inst, fn, state);

    if (snapshot == NULL) {
        return STATUS_ERROR;
    }
    if (size == NULL) {
        return log_error(inst, "%s: the size argument is NULL", fn);
    }
    *size = serialized_size(snapshot);
    return STATUS_OK;
}

Status state_serialize(Instance *inst, const char *fn, const void *state, unsigned char *bytes, size_t size)
{
    const Snapshot *snapshot = checked(inst, fn, state);
    Writer writer = {bytes, 0};
    size_t needed;

    if (snapshot == NULL) {
        return STATUS_ERROR;
    }
    needed = serialized_size(snapshot);
    if (bytes == NULL || size < needed) {
        return log_error(inst, "%s: the buffer of %zu bytes%s is too small for the %zu bytes of this FMU state", fn,
                         size, bytes == NULL ? " (NULL)" : "", needed);
    }
    encode(&writer, snapshot, needed);
    put_uint(&writer, fnv1a(bytes, writer.size), 8);
    return STATUS_OK;
}

/* ------------------------------------------------------------ reading */

typedef struct {
    const unsigned char *at;
    size_t size;
    size_t used;
} Reader;

static bool take_uint(Reader *r, size_t n, uint64_t *value)
{
    size_t i;

    if (r->size - r->used < n) {
        return false;
    }
    *value = 0;
    for (i = 0; i < n; i++) {
        *value |= (uint64_t)r->at[r->used + i] << (8u * i);
    }
    r->used += n;
    return true;
}

static bool take_real(Reader *r, double *value)
{
    uint64_t bits;

    if (!take_uint(r, 8, &bits)) {
        return false;
    }
    memcpy(value, &bits, sizeof bits);
    return true;
}

/* A string's bytes in place (not NUL-terminated) and its length. */
static bool take_text(Reader *r, const unsigned char **text, size_t *n)
{
    uint64_t length;

    if (!take_uint(r, 4, &length) || r->size - r->used < length) {
        return false;
    }
    *text = r->at + r->used;
    *n = (size_t)length;
    r->used += *n;
    return true;
}

static int shown(size_t n)
{
    return n < SHOWN ? (int)n : SHOWN;
}

/* What the bytes are and whom they belong to: everything before the phase. */
static Status check_header(Instance *inst, const char *fn, Reader *r)
{
    const unsigned char *identifier, *token;
    size_t identifier_size, token_size;
    uint64_t format, total, hash, variables, fields;
    Reader tail;

    if (r->size < HEADER_SIZE + HASH_SIZE) {
        return log_error(inst, "%s: %zu bytes are too few for a serialized FMU state (truncated?)", fn, r->size);
    }
    if (memcmp(r->at, MAGIC, sizeof MAGIC) != 0) {
        return log_error(inst, "%s: the bytes are not a serialized FMU state of this framework (bad magic)", fn);
    }
    r->used = sizeof MAGIC;
    take_uint(r, 4, &format);
    take_uint(r, 8, &total);
    if (format != FORMAT_VERSION) {
        return log_error(inst, "%s: the serialized FMU state has format version %llu, this binary reads version %u",
                         fn, (unsigned long long)format, FORMAT_VERSION);
    }
    if (total != r->size) {
        return log_error(inst, "%s: wrong size: the serialized FMU state says it has %llu bytes but %zu were given "
                         "(truncated or extended)", fn, (unsigned long long)total, r->size);
    }
    /* From here on the fields are read from the bytes before the hash only. */
    r->size -= HASH_SIZE;
    tail.at = r->at;
    tail.size = r->size + HASH_SIZE;
    tail.used = r->size;
    take_uint(&tail, HASH_SIZE, &hash);
    if (hash != fnv1a(r->at, r->size)) {
        return log_error(inst, "%s: the serialized FMU state is corrupt (its checksum does not match)", fn);
    }
    if (!take_text(r, &identifier, &identifier_size) || !take_text(r, &token, &token_size)) {
        return log_error(inst, "%s: the serialized FMU state is corrupt (its model name runs past its end)", fn);
    }
    if (identifier_size != strlen(MODEL_IDENTIFIER) || memcmp(identifier, MODEL_IDENTIFIER, identifier_size) != 0
        || token_size != strlen(MODEL_TOKEN) || memcmp(token, MODEL_TOKEN, token_size) != 0) {
        return log_error(inst, "%s: the serialized FMU state is of model '%.*s' (token %.*s), not of this model '%s' "
                         "(token %s)", fn, shown(identifier_size), (const char *)identifier, shown(token_size),
                         (const char *)token, MODEL_IDENTIFIER, MODEL_TOKEN);
    }
    if (!take_uint(r, 4, &variables) || !take_uint(r, 4, &fields)) {
        return log_error(inst, "%s: the serialized FMU state is corrupt (it ends in its header)", fn);
    }
    if (variables != VARIABLE_COUNT || fields != state_field_count()) {
        return log_error(inst, "%s: the serialized FMU state has %llu variables and %llu state fields, this binary "
                         "%u and %u (a build of %s from another model.c?)", fn, (unsigned long long)variables,
                         (unsigned long long)fields, VARIABLE_COUNT, state_field_count(), MODEL_IDENTIFIER);
    }
    return STATUS_OK;
}

static bool take_bool(Reader *r, bool *value)
{
    uint64_t byte;

    if (!take_uint(r, 1, &byte) || byte > 1) {
        return false;
    }
    *value = byte == 1;
    return true;
}

/* value (n bytes) into the object of size bytes at base + offset, false if
   it does not fit there: a table that does not match its struct. */
static bool store(void *base, size_t size, size_t offset, const void *value, size_t n)
{
    if (offset > size || n > size - offset) {
        return false;
    }
    memcpy((unsigned char *)base + offset, value, n);
    return true;
}

/* One value of type tag (a VarType or StateType, told apart by is_variable) from r into base + offset. */
static bool take_value(Reader *r, bool is_variable, int tag, void *base, size_t size, size_t offset,
                       bool *no_memory)
{
    uint64_t number;
    double real;
    bool flag;

    if ((is_variable && tag == VAR_REAL) || (!is_variable && tag == STATE_REAL)) {
        return take_real(r, &real) && store(base, size, offset, &real, sizeof real);
    }
    if ((is_variable && tag == VAR_BOOL) || (!is_variable && tag == STATE_BOOL)) {
        return take_bool(r, &flag) && store(base, size, offset, &flag, sizeof flag);
    }
    if ((is_variable && tag == VAR_INT) || (!is_variable && tag == STATE_INT32)) {
        /* The bits back into an int32_t: two's complement, as int32_t is by definition. */
        int32_t integer;
        uint32_t bits;

        if (!take_uint(r, 4, &number)) {
            return false;
        }
        bits = (uint32_t)number;
        memcpy(&integer, &bits, sizeof integer);
        return store(base, size, offset, &integer, sizeof integer);
    }
    if (!is_variable && tag == STATE_INT64) {
        int64_t integer;

        if (!take_uint(r, 8, &number)) {
            return false;
        }
        memcpy(&integer, &number, sizeof integer);
        return store(base, size, offset, &integer, sizeof integer);
    }
    {
        const unsigned char *text;
        size_t n;
        char *copy;

        if (!take_text(r, &text, &n) || memchr(text, '\0', n) != NULL) {
            return false;
        }
        copy = malloc(n + 1);
        if (copy == NULL) {
            *no_memory = true;
            return false;
        }
        memcpy(copy, text, n);
        copy[n] = '\0';
        if (!store(base, size, offset, &copy, sizeof copy)) {
            free(copy);
            return false;
        }
        return true;
    }
}

/* The values after the header into snapshot (its string slots NULL on entry);
   the name of what is wrong, or NULL. */
static const char *decode(Reader *r, Snapshot *snapshot, bool *no_memory)
{
    const StateFieldInfo *field;
    uint64_t phase;
    unsigned int vr;

    if (!take_uint(r, 4, &phase) || !take_real(r, &snapshot->start_time) || !take_real(r, &snapshot->time)) {
        return "the phase and time";
    }
    if (phase != PHASE_INSTANTIATED && phase != PHASE_INITIALIZATION && phase != PHASE_STEP
        && phase != PHASE_TERMINATED) {
        return "the phase";
    }
    snapshot->phase = (Phase)phase;
    if (!isfinite(snapshot->start_time) || !isfinite(snapshot->time)) {
        return "the time";
    }
    for (vr = 0; vr < VARIABLE_COUNT; vr++) {
        const VariableInfo *info = &MODEL_VARIABLES[vr];

        if (info->causality != CAUSALITY_INDEPENDENT
            && !take_value(r, true, (int)info->type, &snapshot->var, sizeof snapshot->var, info->offset,
                           no_memory)) {
            return info->name;
        }
    }
    for (field = MODEL_STATE_FIELDS; field->name != NULL; field++) {
        if (!take_value(r, false, (int)field->type, &snapshot->state, sizeof snapshot->state, field->offset,
                        no_memory)) {
            return field->name;
        }
    }
    return r->used == r->size ? NULL : "its end (bytes left over)";
}

Status state_deserialize(Instance *inst, const char *fn, const unsigned char *bytes, size_t size, void **state)
{
    Reader reader = {bytes, size, 0};
    Snapshot *snapshot;
    const char *wrong;
    bool no_memory = false;

    if (state == NULL || (size > 0 && bytes == NULL)) {
        return log_error(inst, "%s: the %s argument is NULL", fn, state == NULL ? "FMU state" : "bytes");
    }
    if (*state != NULL && checked(inst, fn, *state) == NULL) {
        return STATUS_ERROR;
    }
    if (check_header(inst, fn, &reader) != STATUS_OK) {
        return STATUS_ERROR;
    }
    snapshot = calloc(1, sizeof *snapshot);
    if (snapshot == NULL) {
        return log_error(inst, "%s: out of memory allocating an FMU state", fn);
    }
    snapshot->owner = OWNER;
    null_strings(&snapshot->var); /* calloc's zero bits need not be NULL pointers in C99 */
    wrong = decode(&reader, snapshot, &no_memory);
    if (wrong != NULL) {
        free_strings(&snapshot->var);
        free(snapshot);
        if (no_memory) {
            return log_error(inst, "%s: out of memory copying '%s' out of the serialized FMU state", fn, wrong);
        }
        return log_error(inst, "%s: the serialized FMU state is corrupt at %s", fn, wrong);
    }
    put(state, snapshot);
    return STATUS_OK;
}
