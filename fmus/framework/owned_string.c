/* Heap copies of strings the instance owns (its name, string variables). */
#include <stdlib.h>
#include <string.h>

#include "owned_string.h"

/* strdup is POSIX, not C99. */
char *owned_string_copy(const char *text)
{
    size_t size = strlen(text) + 1;
    char *copy = malloc(size);

    if (copy != NULL) {
        memcpy(copy, text, size);
    }
    return copy;
}
