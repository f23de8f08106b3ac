/* FMU states: copies of an instance's whole state and their serialized form, for both FMI versions. */
#ifndef STATE_H
#define STATE_H

#include <stddef.h>

#include "instance.h"
#include "status.h"

/* An FMU state is handed to the importer as the void * that fmi2FMUstate and
   fmi3FMUState both are; it holds the phase, start time, time, every variable
   (strings copied) and the model's private state, and owns its strings.

   fn names the FMI function in messages. *state may be NULL (a new state is
   made) or a state this instance gave before (it is overwritten in place, as
   FMI allows). */
Status state_get(Instance *inst, const char *fn, void **state);

/* Make inst what it was when state was taken; allowed after an error too, so
   that an importer can go back to a state saved before it (FMI 2.0 p. 22). */
Status state_set(Instance *inst, const char *fn, const void *state);

/* Free *state (NULL is ignored) and set it to NULL. */
Status state_free(Instance *inst, const char *fn, void **state);

Status state_serialized_size(Instance *inst, const char *fn, const void *state, size_t *size);
Status state_serialize(Instance *inst, const char *fn, const void *state, unsigned char *bytes, size_t size);

/* Bytes of another model, of another build of it, of a wrong size, with a bad
   magic or checksum are refused with the cause in the log. */
Status state_deserialize(Instance *inst, const char *fn, const unsigned char *bytes, size_t size, void **state);

#endif
