#include "memory.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static uint64_t physical_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    return pages > 0 && page > 0 ? (uint64_t)pages * (uint64_t)page : UINT64_MAX;
}

/* MemAvailable in bytes, 0 if unknown (old kernels, no /proc). */
static uint64_t meminfo_available(void)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f)
        return 0;
    char line[256];
    unsigned long long kb = 0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1)
            break;
    fclose(f);
    return (uint64_t)kb * 1024;
}

uint64_t sg_memory_available(void)
{
    uint64_t bytes = meminfo_available();
    if (bytes == 0)
        bytes = physical_memory();
    const char *limit = getenv("SG_MEMORY_LIMIT_MB");
    if (limit && *limit) {
        char *end;
        double mb = strtod(limit, &end);
        if (!*end && mb >= 0 && mb * 1048576.0 < (double)bytes)
            bytes = (uint64_t)(mb * 1048576.0);
    }
    return bytes;
}

bool sg_memory_check(double bytes, const char *name, const char *what, SgError *err)
{
    uint64_t available = sg_memory_available();
    if (bytes <= (double)available)
        return true;
    return sg_fail(err, "%s%s%s needs %.0f MB of memory, more than the %.0f MB available", name ? name : "",
                   name ? ": " : "", what, bytes / 1048576.0, (double)available / 1048576.0);
}

void sg_memory_prefer_huge_pages(void *p, size_t bytes)
{
    /* only the whole 2 MB pages inside the block; a no-op where the kernel
     * has no transparent huge pages (or they are off) */
    const uintptr_t huge = (uintptr_t)2 << 20;
    if (!p || bytes < 4 * huge)
        return;
    uintptr_t lo = ((uintptr_t)p + huge - 1) & ~(huge - 1);
    uintptr_t hi = ((uintptr_t)p + bytes) & ~(huge - 1);
    if (hi > lo)
        (void)madvise((void *)lo, hi - lo, MADV_HUGEPAGE);
}

bool sg_reserve(void **array, size_t *capacity, size_t needed, size_t item_size, size_t first)
{
    if (needed <= *capacity)
        return true;
    size_t cap = *capacity ? *capacity : first;
    while (cap < needed) {
        if (cap > SIZE_MAX / 2)
            return false;
        cap *= 2;
    }
    if (cap > SIZE_MAX / item_size)
        return false;
    void *grown = realloc(*array, cap * item_size);
    if (!grown)
        return false;
    *array = grown;
    *capacity = cap;
    return true;
}
