/* Memory budget: work that cannot fit is refused up front with a clear
 * message. Linux overcommits, so a large calloc succeeds and the process
 * is killed later when it touches the pages; a step therefore estimates
 * its peak from the grid size and checks it here before allocating. */
#ifndef SG_MEMORY_H
#define SG_MEMORY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bytes this process may plan to use: MemAvailable (/proc/meminfo), else
 * the physical memory. SG_MEMORY_LIMIT_MB in the environment lowers it
 * (tests simulate a small machine with it). */
uint64_t sg_memory_available(void);

/* Fails with "NAME: WHAT needs N MB of memory, more than the M MB
 * available" when bytes exceeds sg_memory_available(). name may be NULL. */
bool sg_memory_check(double bytes, const char *name, const char *what, SgError *err);

/* Asks for transparent huge pages on a large block just allocated and not
 * yet written (2 MB pages: the arrays the skeleton's collapse and the
 * nearest-node propagation read at random, hundreds of MB at resolution
 * 1000, would otherwise miss the TLB on nearly every access). */
void sg_memory_prefer_huge_pages(void *p, size_t bytes);

/* Grows *array, *capacity items of item_size bytes, to hold at least
 * `needed` items: its capacity doubles, from `first`. False, the array as it
 * was, when memory runs out or the size overflows. */
bool sg_reserve(void **array, size_t *capacity, size_t needed, size_t item_size, size_t first);

#ifdef __cplusplus
}
#endif
#endif
