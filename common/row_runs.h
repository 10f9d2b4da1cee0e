/* Runs along x, row by row, joined by union-find: a grid's regions (the
 * air of a medium, the space a complex's squares bound) labelled a run at
 * a time instead of a voxel at a time, far cheaper than a flood. The caller
 * says what a run is (sg_row_runs_push, row by row in order) and which
 * runs of two rows touch (sg_row_runs_connect); rows are numbered y + ny z
 * or any order the caller likes. */
#ifndef SG_ROW_RUNS_H
#define SG_ROW_RUNS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct SgRun {
    uint32_t start, end; /* inclusive x range */
} SgRun;

typedef struct SgRowRuns {
    size_t rows;
    uint32_t count;
    size_t capacity;
    SgRun *run;            /* row by row, by x within a row */
    uint32_t *parent;      /* union-find over runs (sg_set_find) */
    uint32_t *row_first;   /* rows + 1 offsets: row r's runs are [row_first[r], row_first[r + 1]) */
} SgRowRuns;

/* Empty runs over `rows` rows; false when out of memory. */
bool sg_row_runs_begin(SgRowRuns *r, size_t rows);
/* Row `row` starts here: its runs are the ones pushed until the next. */
static inline void sg_row_runs_start_row(SgRowRuns *r, size_t row)
{
    r->row_first[row] = r->count;
}
/* Appends the run x0..x1 (inclusive) to the current row. */
bool sg_row_runs_push(SgRowRuns *r, uint32_t x0, uint32_t x1);
/* After the last row: every run its own set; false when out of memory. */
bool sg_row_runs_end(SgRowRuns *r);
void sg_row_runs_release(SgRowRuns *r);

/* Joins each run of row ra to each run of row rb that it overlaps once
 * widened by `reach` (0: they share an x; 1: they touch, even diagonally)
 * and, when `open` is given, wherever open(ctx, lo, hi) says the shared x
 * range lo..hi lets them meet (lo > hi when they only touch). */
typedef bool (*SgRowRunsOpen)(const void *ctx, uint32_t lo, uint32_t hi);
void sg_row_runs_connect(SgRowRuns *r, size_t ra, size_t rb, uint32_t reach, SgRowRunsOpen open,
                         const void *ctx);

/* The last run of `row` starting at or before x (the run holding x when
 * one does), or UINT32_MAX when none does. */
uint32_t sg_row_runs_at(const SgRowRuns *r, size_t row, uint32_t x);

#endif
