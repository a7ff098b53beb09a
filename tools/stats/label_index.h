/*
 * label_index.h - labels (group, unit, subject names) to dense ids 0, 1, 2, ... in
 * order of first appearance, by an open-addressing hash table: O(1) expected per
 * look-up, so n rows with n distinct labels cost O(n), not the O(n^2) of comparing
 * each new label with every earlier one (100,000 distinct labels took 34 s that way,
 * 200,000 took 95 s; session 81 review).
 *
 * Keys are borrowed, not copied: they must outlive the index (palp-stats passes CSV
 * cells). Labels are compared exactly (bytes, case included).
 */
#ifndef PALP_TOOLS_LABEL_INDEX_H
#define PALP_TOOLS_LABEL_INDEX_H

#include <stddef.h>

typedef struct label_index {
  size_t cap;         /* slots, a power of two, at least twice the labels held */
  size_t count;       /* labels held = the next id */
  const char **key;   /* [cap], NULL = free slot */
  int *id;            /* [cap] */
} label_index;

/* An empty index; returns 0, or -1 when out of memory. */
int label_index_init(label_index *t, size_t expected);
/* The id of key, adding it with id t->count when new (*added set to 1, else 0).
 * Returns -1 when out of memory or when more than INT_MAX labels. */
int label_index_get(label_index *t, const char *key, int *added);
void label_index_free(label_index *t);

#endif
