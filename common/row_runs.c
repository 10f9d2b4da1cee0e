#include "row_runs.h"

#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "union_find.h"

bool sg_row_runs_begin(SgRowRuns *r, size_t rows)
{
    memset(r, 0, sizeof *r);
    r->rows = rows;
    r->row_first = malloc((rows + 1) * sizeof *r->row_first);
    return r->row_first != NULL;
}

bool sg_row_runs_push(SgRowRuns *r, uint32_t x0, uint32_t x1)
{
    if (r->count == UINT32_MAX ||
        !sg_reserve((void **)&r->run, &r->capacity, (size_t)r->count + 1, sizeof *r->run, 4096))
        return false;
    r->run[r->count++] = (SgRun){x0, x1};
    return true;
}

bool sg_row_runs_end(SgRowRuns *r)
{
    r->row_first[r->rows] = r->count;
    r->parent = malloc((r->count ? r->count : 1) * sizeof *r->parent);
    if (!r->parent)
        return false;
    for (uint32_t i = 0; i < r->count; i++)
        r->parent[i] = i;
    return true;
}

void sg_row_runs_release(SgRowRuns *r)
{
    free(r->run);
    free(r->parent);
    free(r->row_first);
    memset(r, 0, sizeof *r);
}

void sg_row_runs_connect(SgRowRuns *r, size_t ra, size_t rb, uint32_t reach, SgRowRunsOpen open,
                         const void *ctx)
{
    uint32_t a = r->row_first[ra], a_end = r->row_first[ra + 1];
    uint32_t b = r->row_first[rb], b_end = r->row_first[rb + 1];
    while (a < a_end && b < b_end) {
        SgRun run_a = r->run[a], run_b = r->run[b];
        uint32_t lo = run_a.start > run_b.start ? run_a.start : run_b.start;
        uint32_t hi = run_a.end < run_b.end ? run_a.end : run_b.end;
        if (lo <= hi + reach && (!open || open(ctx, lo, hi)))
            sg_set_union(r->parent, a, b);
        if (run_a.end < run_b.end)
            a++;
        else
            b++;
    }
}

uint32_t sg_row_runs_at(const SgRowRuns *r, size_t row, uint32_t x)
{
    /* the first run of the row starting after x; the one before it */
    uint32_t first = r->row_first[row], lo = first, hi = r->row_first[row + 1];
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (r->run[mid].start <= x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo > first ? lo - 1 : UINT32_MAX;
}
