/* Heap copies of strings the instance owns (its name, string variables). */
#ifndef OWNED_STRING_H
#define OWNED_STRING_H

/* A malloc'ed copy of text, or NULL if out of memory. */
char *owned_string_copy(const char *text);

#endif
