/* Directional parallel collapse [CC09], 1D variant with the lifespan /
 * opening rule [Cha10].
 *
 * A step runs 18 sub-steps: direction x, y, z; orientation +, -; coface
 * dimension 3, 2, 1. Sub-step s removes, at once, every free pair of its
 * kind that was free when it began (CC09: such pairs cannot interfere).
 * Free faces wait in 18 queues (flat uint32 arrays of cell ids); a face is
 * queued when it becomes free, which can only happen when one of its
 * cofaces is removed, so after a removal only the faces of the removed
 * cells are re-tested: each step costs the size of the current border.
 * A face is queued when, right after one of its cofaces goes, it has
 * exactly one coface left (or at the start). Cofaces only ever go, so that
 * count passes 1 once: a cell is queued at most once, with no need for a
 * "queued" bit per cell. A queued face may stop being free (its coface
 * goes with another face): it is checked again when its sub-step comes.
 *
 * Threads: a large sub-step is verified in parallel (read only), then its
 * pairs are processed by slabs of lattice planes, all even slabs at once,
 * then all odd ones; slabs running together touch disjoint cells, so this
 * is just one of the sequential orders, and no atomics are needed. */
#include "collapse.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "row_runs.h"
#include "threads.h"
#include "union_find.h"

#define KINDS 18
#define SORT_BUCKETS 4096
#define SQUARE_BITS 0x68u /* masks 3, 5, 6 */

typedef struct U32Vec {
    uint32_t *a;
    size_t n, cap;
} U32Vec;

typedef struct EdgeVec {
    SgIsolatedEdge *a;
    size_t n, cap;
} EdgeVec;

/* Where a pass over removed pairs sends what it finds: the collapse's own
 * queues and lists (sequential), or a worker's (parallel). */
typedef struct Sink {
    U32Vec *cur, *next; /* KINDS queues each */
    EdgeVec *noted;
    bool oom;
} Sink;

typedef struct Worker {
    U32Vec pairs;
    U32Vec cur[KINDS], next[KINDS];
    EdgeVec noted;
    Sink sink;
} Worker;

/* The constraint set is a few cells per skeleton node (anchors and kept
 * edges, 0- and 1-cells), so a small open-addressing set of cell ids
 * rather than a byte per lattice vertex: no memory per voxel, and the
 * table stays in cache while the byte array's line was one more miss per
 * tested face. Cells of dimension 2 and 3 are looked up only if one was
 * ever constrained. */
typedef struct CellSet {
    uint32_t *slot; /* UINT32_MAX: empty */
    size_t count;
    int bits;       /* 2^bits slots */
    bool high_dims; /* a 2- or 3-cell is in the set */
} CellSet;

static inline size_t cell_slot(const CellSet *s, uint32_t cell)
{
    return (size_t)(((uint64_t)cell * 0x9E3779B97F4A7C15ull) >> (64 - s->bits));
}

/* Masks of dimension 0 and 1 (0, 1, 2, 4) as bits. */
#define LOW_DIM_MASKS 0x17u

static inline bool cell_set_has(const CellSet *s, uint32_t cell)
{
    if (!s->high_dims && !(LOW_DIM_MASKS >> (cell & 7) & 1))
        return false;
    size_t mask = ((size_t)1 << s->bits) - 1;
    for (size_t i = cell_slot(s, cell);; i = (i + 1) & mask) {
        uint32_t x = s->slot[i];
        if (x == cell)
            return true;
        if (x == UINT32_MAX)
            return false;
    }
}

static bool cell_set_add(CellSet *s, uint32_t cell)
{
    if (4 * (s->count + 1) > ((size_t)1 << s->bits)) { /* a quarter full: short misses */
        CellSet grown = {NULL, 0, s->bits + 1, s->high_dims};
        grown.slot = malloc(((size_t)1 << grown.bits) * sizeof *grown.slot);
        if (!grown.slot)
            return false;
        memset(grown.slot, 0xff, ((size_t)1 << grown.bits) * sizeof *grown.slot);
        for (size_t i = 0; i < ((size_t)1 << s->bits); i++)
            if (s->slot[i] != UINT32_MAX) {
                size_t j = cell_slot(&grown, s->slot[i]);
                while (grown.slot[j] != UINT32_MAX)
                    j = (j + 1) & (((size_t)1 << grown.bits) - 1);
                grown.slot[j] = s->slot[i];
                grown.count++;
            }
        free(s->slot);
        *s = grown;
    }
    size_t mask = ((size_t)1 << s->bits) - 1;
    size_t i = cell_slot(s, cell);
    while (s->slot[i] != UINT32_MAX && s->slot[i] != cell)
        i = (i + 1) & mask;
    if (s->slot[i] == UINT32_MAX)
        s->count++;
    s->slot[i] = cell;
    s->high_dims |= sg_cell_dim(cell & 7) >= 2;
    return true;
}

static bool cell_set_init(CellSet *s)
{
    s->bits = 10;
    s->count = 0;
    s->high_dims = false;
    s->slot = malloc(((size_t)1 << s->bits) * sizeof *s->slot);
    if (s->slot)
        memset(s->slot, 0xff, ((size_t)1 << s->bits) * sizeof *s->slot);
    return s->slot != NULL;
}

typedef enum Job { JOB_VERIFY, JOB_EVEN, JOB_ODD, JOB_EXIT } Job;

typedef struct Collapse Collapse;
typedef struct Helper {
    Collapse *c;
    int t;
} Helper;

#define MAX_THREADS 8
/* Slabs of lattice planes processed concurrently are at least this thick
 * and never adjacent: the work for a pair at plane z reads and writes
 * planes z-2..z+1 only. */
#define SLAB_MIN 8

struct Collapse {
    SgComplex *cx;
    uint8_t *cells;
    CellSet cons;       /* the constraint set: lights, camera, kept edges */
    size_t st[3];
    U32Vec queue_a[KINDS], queue_b[KINDS];
    U32Vec *cur, *next; /* this step's and next step's queues */
    U32Vec pairs;       /* f, g, f, g, ... */
    U32Vec sort_scratch; /* ordering a queue */
    size_t sort_count[SORT_BUCKETS + 1];
    uint64_t cell_limit;  /* cell ids are below this */
    EdgeVec live;       /* isolated edges not yet kept */
    EdgeVec kept;       /* isolated edges in the constraint set */
    const uint16_t *dist8, *open8; /* lattice layout: voxel at its lower corner */
    int substep;
    int32_t step;
    uint64_t squares, removed, total;
    uint32_t cavities_broken_total, forced_total;
    int64_t filter256;
    bool oom;
    /* parallel sub-steps */
    int threads;
    size_t parallel_grain;
    Worker *workers;
    pthread_barrier_t start, end;
    pthread_mutex_t gate_lock;
    pthread_cond_t gate;
    bool gate_open;
    Job job;
    const U32Vec *job_queue;
    size_t slab_planes, slab_count;
    size_t *slab_start;      /* pairs of slab i: pairs.a[2*slab_start[i] .. 2*slab_start[i+1]) */
    _Atomic size_t next_slab;
};

/* the first capacity of the collapse's growing arrays */
#define VEC_FIRST 256

static inline bool vec_push_u32(U32Vec *v, uint32_t x)
{
    if (v->n == v->cap && !sg_reserve((void **)&v->a, &v->cap, v->n + 1, sizeof *v->a, VEC_FIRST))
        return false;
    v->a[v->n++] = x;
    return true;
}

static inline bool vec_push_edge(EdgeVec *v, SgIsolatedEdge e)
{
    if (v->n == v->cap && !sg_reserve((void **)&v->a, &v->cap, v->n + 1, sizeof *v->a, VEC_FIRST))
        return false;
    v->a[v->n++] = e;
    return true;
}

static inline void u32_push(Collapse *c, U32Vec *v, uint32_t x)
{
    if (v->n == v->cap && !sg_reserve((void **)&v->a, &v->cap, v->n + 1, sizeof *v->a, VEC_FIRST)) {
        c->oom = true;
        return;
    }
    v->a[v->n++] = x;
}

static inline void edge_push(Collapse *c, EdgeVec *v, SgIsolatedEdge e)
{
    if (v->n == v->cap && !sg_reserve((void **)&v->a, &v->cap, v->n + 1, sizeof *v->a, VEC_FIRST)) {
        c->oom = true;
        return;
    }
    v->a[v->n++] = e;
}

static inline bool has(const uint8_t *bits, size_t v, unsigned m)
{
    return bits[v] >> m & 1;
}

/* For a face mask m: bit m | 1 << a of byte 0 and of byte 1 + a, for each
 * axis a not in m (free_kind's coface word). */
#define COFACE_BITS(m, a) ((m) >> (a) & 1 ? 0u : (1u << ((m) | 1u << (a))) * (1u | 1u << (8 * ((a) + 1))))
#define COFACE_MASK(m) (COFACE_BITS(m, 0) | COFACE_BITS(m, 1) | COFACE_BITS(m, 2))
static const uint32_t coface_bits[8] = {COFACE_MASK(0u), COFACE_MASK(1u), COFACE_MASK(2u),
                                        COFACE_MASK(3u), COFACE_MASK(4u), COFACE_MASK(5u),
                                        COFACE_MASK(6u), COFACE_MASK(7u)};

static inline uint32_t coface_word(const Collapse *c, size_t v, unsigned m)
{
    const uint8_t *cells = c->cells;
    uint32_t word = (uint32_t)cells[v] | (uint32_t)cells[v - c->st[0]] << 8 |
                    (uint32_t)cells[v - c->st[1]] << 16 | (uint32_t)cells[v - c->st[2]] << 24;
    return word & coface_bits[m];
}

/* Kind (0..17) of the free pair with face f, or -1 if f is not a free,
 * removable face; *g receives the coface. */
/* Inlined into its callers: a call saved and restored six registers,
 * which on the collapse's hundreds of millions of tests was a seventh of
 * its instructions. */
static inline __attribute__((always_inline)) int free_kind(const Collapse *c, uint32_t f,
                                                           uint32_t *g)
{
    size_t v = f >> 3;
    unsigned m = f & 7;
    const uint8_t *cells = c->cells;
    if (!has(cells, v, m))
        return -1;
    /* The cofaces as bits of one word, with no branch per axis: byte 0 is
     * v's cells (the cofaces above f), byte 1 + a the cells of the vertex
     * below v along axis a (the coface below along a); coface_bits[m] keeps
     * the coface masks m | 1 << a, for the axes a not in m. */
    uint32_t word = coface_word(c, v, m);
    if (word == 0 || (word & (word - 1)) != 0)
        return -1; /* no coface, or more than one */
    int bit = __builtin_ctz(word);
    unsigned gm = (unsigned)bit & 7;
    int below = bit >> 3; /* 0: above; 1 + a: below along a */
    int axis = __builtin_ctz(gm ^ m), ori = below != 0;
    size_t gv = v - (below ? c->st[axis] : 0);
    /* the constraints last: most faces tested have no or two cofaces */
    if (cell_set_has(&c->cons, f) || cell_set_has(&c->cons, (uint32_t)(gv * 8 + gm)))
        return -1;
    *g = (uint32_t)(gv * 8 + gm);
    /* sub-step of the pair: coface dimension 3, 2, 1 -> 0, 1, 2 */
    static const uint8_t coface_rank[8] = {0, 2, 2, 1, 2, 1, 1, 0};
    return axis * 6 + ori * 3 + coface_rank[gm];
}

static inline __attribute__((always_inline)) void consider(const Collapse *c, Sink *sk,
                                                           uint32_t h)
{
    uint32_t g;
    int k = free_kind(c, h, &g);
    if (k < 0)
        return;
    if (!vec_push_u32(k > c->substep ? &sk->cur[k] : &sk->next[k], h))
        sk->oom = true;
}

/* The faces of a cell (one dimension lower), two per axis it spans: at its
 * vertex and one step along the axis. Returns how many (at most 6). */
static inline int cell_faces(const Collapse *c, uint32_t cell, uint32_t faces[6])
{
    size_t v = cell >> 3;
    unsigned m = cell & 7;
    int n = 0;
    /* over the axes of m by its set bits (as many in every call of a
     * sub-step: a branch on each axis mispredicted) */
    for (unsigned axes = m; axes; axes &= axes - 1) {
        int a = __builtin_ctz(axes);
        unsigned fm = m ^ 1u << a;
        faces[n++] = (uint32_t)(v * 8 + fm);
        faces[n++] = (uint32_t)((v + c->st[a]) * 8 + fm);
    }
    return n;
}

static inline void consider_faces(const Collapse *c, Sink *sk, uint32_t cell)
{
    uint32_t faces[6];
    int n = cell_faces(c, cell, faces);
    for (int i = 0; i < n; i++)
        consider(c, sk, faces[i]);
}

static uint16_t edge_opening(const Collapse *c, size_t v, unsigned m)
{
    /* the voxels holding edge (v, m): cubes at v - d, d sharing no axis with m */
    uint16_t best = 0;
    unsigned free_axes = 7u & ~m;
    for (unsigned d = free_axes;; d = (d - 1) & free_axes) { /* the subsets of free_axes */
        size_t w = v - (d & 1) * c->st[0] - (d >> 1 & 1) * c->st[1] - (d >> 2 & 1) * c->st[2];
        if (c->open8[w] > best)
            best = c->open8[w];
        if (d == 0)
            break;
    }
    return best;
}

/* A square was removed: record its edges that have no square left. */
static void note_isolated_edges(const Collapse *c, Sink *sk, uint32_t square)
{
    uint32_t edges[6];
    int n = cell_faces(c, square, edges);
    for (int i = 0; i < n; i++) {
        size_t w = edges[i] >> 3;
        unsigned em = edges[i] & 7;
        if (!has(c->cells, w, em) || coface_word(c, w, em) != 0)
            continue; /* gone, or a square is left */
        SgIsolatedEdge noted = {edges[i], c->step, -1, edge_opening(c, w, em)};
        if (!vec_push_edge(sk->noted, noted))
            sk->oom = true;
    }
}

static void remove_cell(const Collapse *c, uint32_t cell)
{
    c->cells[cell >> 3] &= (uint8_t) ~(1u << (cell & 7));
}

/* Removes pairs [lo, hi) of c->pairs one by one, noting isolated edges and
 * queueing newly free faces. The pairs were all tested against the complex
 * as the sub-step found it, so removing them in any order gives the same
 * complex; noting an edge right after each square goes notes it exactly
 * once (when its last square goes); a face tested too early is tested
 * again when its other coface goes. */
static void process_pairs(const Collapse *c, Sink *sk, size_t lo, size_t hi)
{
    int coface_dim = 3 - c->substep % 3;
    for (size_t i = lo; i < hi; i++) {
        uint32_t f = c->pairs.a[2 * i], g = c->pairs.a[2 * i + 1];
        remove_cell(c, f);
        remove_cell(c, g);
        /* coface_dim 3: each edge of the square f is also an edge of
         * another square of the cube g, still here: none becomes isolated */
        if (coface_dim == 2)
            note_isolated_edges(c, sk, g);
        consider_faces(c, sk, g);
        consider_faces(c, sk, f);
    }
}

static void run_job(Collapse *c, int t)
{
    Worker *w = &c->workers[t];
    if (c->job == JOB_VERIFY) {
        const U32Vec *q = c->job_queue;
        size_t lo = q->n * (size_t)t / (size_t)c->threads;
        size_t hi = q->n * (size_t)(t + 1) / (size_t)c->threads;
        for (size_t i = lo; i < hi; i++) {
            uint32_t f = q->a[i], g = 0;
            if (free_kind(c, f, &g) == c->substep &&
                (!vec_push_u32(&w->pairs, f) || !vec_push_u32(&w->pairs, g)))
                w->sink.oom = true;
        }
        return;
    }
    /* slabs of one parity: any two are separated by a slab of the other */
    size_t parity = c->job == JOB_ODD;
    for (;;) {
        size_t k = atomic_fetch_add(&c->next_slab, 1);
        size_t slab = 2 * k + parity;
        if (slab >= c->slab_count)
            break;
        process_pairs(c, &w->sink, c->slab_start[slab], c->slab_start[slab + 1]);
    }
}

static void *helper_main(void *arg)
{
    Helper *h = arg;
    Collapse *c = h->c;
    pthread_mutex_lock(&c->gate_lock);
    while (!c->gate_open)
        pthread_cond_wait(&c->gate, &c->gate_lock);
    pthread_mutex_unlock(&c->gate_lock);
    for (;;) {
        pthread_barrier_wait(&c->start);
        if (c->job == JOB_EXIT)
            break;
        run_job(c, h->t);
        pthread_barrier_wait(&c->end);
    }
    return NULL;
}

static void run_parallel(Collapse *c, Job job)
{
    c->job = job;
    atomic_store(&c->next_slab, 0);
    pthread_barrier_wait(&c->start);
    run_job(c, 0);
    pthread_barrier_wait(&c->end);
}

static bool append_u32(U32Vec *dst, U32Vec *src)
{
    if (src->n == 0)
        return true;
    if (!sg_reserve((void **)&dst->a, &dst->cap, dst->n + src->n, sizeof *dst->a, VEC_FIRST))
        return false;
    memcpy(dst->a + dst->n, src->a, src->n * sizeof *src->a);
    dst->n += src->n;
    src->n = 0;
    if (src->cap > (1u << 16)) { /* a worker's copy of a large queue: do not keep it */
        free(src->a);
        *src = (U32Vec){0};
    }
    return true;
}

/* The sub-step on the worker threads: verify (read only), sort the pairs
 * into slabs of lattice planes, then process even slabs concurrently and
 * odd slabs concurrently. Slabs running together touch disjoint cells, so
 * this is one of the sequential orders; queues get the same sets (in
 * another order), and the collapse depends on the sets only: the result
 * does not depend on the threads. */
static void run_substep_parallel(Collapse *c, U32Vec *q)
{
    c->job_queue = q;
    run_parallel(c, JOB_VERIFY);
    q->n = 0;
    size_t total = 0;
    for (int t = 0; t < c->threads; t++) {
        c->oom |= c->workers[t].sink.oom;
        total += c->workers[t].pairs.n;
    }
    if (c->oom || !sg_reserve((void **)&c->pairs.a, &c->pairs.cap, total, sizeof *c->pairs.a, VEC_FIRST)) {
        c->oom = true;
        return;
    }
    /* counting sort of the pairs by the slab of their face's plane */
    size_t *start = c->slab_start;
    memset(start, 0, (c->slab_count + 1) * sizeof *start);
    for (int t = 0; t < c->threads; t++) {
        const U32Vec *p = &c->workers[t].pairs;
        for (size_t i = 0; i < p->n; i += 2)
            start[(p->a[i] >> 3) / c->st[2] / c->slab_planes + 1]++;
    }
    for (size_t i = 1; i <= c->slab_count; i++)
        start[i] += start[i - 1];
    for (int t = 0; t < c->threads; t++) {
        U32Vec *p = &c->workers[t].pairs;
        for (size_t i = 0; i < p->n; i += 2) {
            size_t at = start[(p->a[i] >> 3) / c->st[2] / c->slab_planes]++;
            c->pairs.a[2 * at] = p->a[i];
            c->pairs.a[2 * at + 1] = p->a[i + 1];
        }
        p->n = 0;
        if (p->cap > (1u << 16)) {
            free(p->a);
            *p = (U32Vec){0};
        }
    }
    for (size_t i = c->slab_count; i > 0; i--) /* back to slab starts */
        start[i] = start[i - 1];
    start[0] = 0;
    c->pairs.n = total;
    run_parallel(c, JOB_EVEN);
    run_parallel(c, JOB_ODD);
    c->removed += total;
    if (3 - c->substep % 3 >= 2)
        c->squares -= total / 2;
    for (int t = 0; t < c->threads && !c->oom; t++) {
        Worker *w = &c->workers[t];
        c->oom |= w->sink.oom;
        for (int k = 0; k < KINDS && !c->oom; k++)
            if (!append_u32(&c->cur[k], &w->cur[k]) || !append_u32(&c->next[k], &w->next[k]))
                c->oom = true;
        for (size_t i = 0; i < w->noted.n && !c->oom; i++)
            edge_push(c, &c->live, w->noted.a[i]);
        w->noted.n = 0;
    }
}

/* Orders a queue by windows of cell ids (one counting pass on the high
 * bits: SORT_BUCKETS windows over the lattice), so that the sub-step walks
 * the border in memory order: a queue gathers the faces freed by up to 18
 * earlier sub-steps, each in its own sweep of the grid, and on a grid
 * larger than the cache every sweep reloads the lines the others loaded.
 * Within a window (a few lattice rows) the order is left as it came: the
 * window's cells stay in cache, and a full sort took three passes. The
 * result depends on the queue's set only (header). */
static void sort_queue(Collapse *c, U32Vec *q)
{
    if (q->n < 4096)
        return;
    if (!sg_reserve((void **)&c->sort_scratch.a, &c->sort_scratch.cap, q->n, sizeof *q->a, VEC_FIRST))
        return; /* unsorted is still correct */
    int shift = 0;
    while ((c->cell_limit >> shift) >= SORT_BUCKETS)
        shift++;
    const uint32_t *from = q->a;
    uint32_t *to = c->sort_scratch.a;
    size_t *count = c->sort_count;
    memset(count, 0, (SORT_BUCKETS + 1) * sizeof *count);
    for (size_t i = 0; i < q->n; i++)
        count[(from[i] >> shift) + 1]++;
    for (int b = 0; b < SORT_BUCKETS; b++)
        count[b + 1] += count[b];
    for (size_t i = 0; i < q->n; i++)
        to[count[from[i] >> shift]++] = from[i];
    U32Vec sorted = {to, q->n, c->sort_scratch.cap};
    c->sort_scratch = (U32Vec){q->a, 0, q->cap};
    *q = sorted;
}

static void run_substep(Collapse *c, int s)
{
    c->substep = s;
    U32Vec *q = &c->cur[s];
    sort_queue(c, q);
    if (c->threads > 1 && q->n >= c->parallel_grain) {
        run_substep_parallel(c, q);
    } else {
        c->pairs.n = 0;
        for (size_t i = 0; i < q->n; i++) {
            uint32_t f = q->a[i], g;
            if (free_kind(c, f, &g) == s) {
                u32_push(c, &c->pairs, f);
                u32_push(c, &c->pairs, g);
            }
        }
        q->n = 0;
        if (c->oom)
            return;
        size_t n = c->pairs.n / 2;
        c->removed += 2 * n;
        if (3 - s % 3 >= 2)
            c->squares -= n;
        Sink sink = {c->cur, c->next, &c->live, false};
        process_pairs(c, &sink, 0, n);
        c->oom |= sink.oom;
    }
    if (q->cap > (1u << 16)) { /* the border moves on: do not keep the slack */
        free(q->a);
        q->a = NULL;
        q->cap = 0;
    }
}

static int compare_edge_cell(const void *a, const void *b)
{
    uint32_t x = ((const SgIsolatedEdge *)a)->cell, y = ((const SgIsolatedEdge *)b)->cell;
    return (x > y) - (x < y);
}

/* After step l: an isolated edge with l - birth(e) > opening(e) is kept. */
static void apply_lifespan_rule(Collapse *c)
{
    EdgeVec *live = &c->live;
    size_t w = 0;
    for (size_t i = 0; i < live->n; i++) {
        SgIsolatedEdge e = live->a[i];
        size_t v = e.cell >> 3;
        unsigned m = e.cell & 7;
        if (!has(c->cells, v, m))
            continue;
        if ((int64_t)(c->step - e.birth) * 8 * 256 > (int64_t)e.open8 * c->filter256) {
            if (!cell_set_add(&c->cons, e.cell))
                c->oom = true;
            e.kept = c->step;
            edge_push(c, &c->kept, e);
            continue;
        }
        live->a[w++] = e;
    }
    live->n = w;
}

/* ---- cavities ---------------------------------------------------------- */

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

static uint16_t voxel_dist8(const Collapse *c, size_t v)
{
    return c->dist8[v];
}

/* The regions of space the squares left bound: lattice vertices (each the
 * unit cube of space at its lower corner), joined to their 6 neighbours
 * unless a square lies between them; the far padding layer owns no voxel
 * and is left out. Labelled by union-find over x-runs, scanning the cells
 * in memory order (a flood from each square visited the lattice in
 * breadth-first order, a cache miss per vertex on large grids). The
 * partition is the same, so the same squares are removed. */
static size_t space_rows_y(const Collapse *c)
{
    return (size_t)c->cx->ly - 1; /* without the far padding */
}

/* Two runs of neighbouring rows meet wherever a vertex of the upper row is
 * not walled off from the one under it by a square of normal `wall`. */
typedef struct SpaceWall {
    const uint8_t *cells;
    size_t first_vertex; /* of the upper row */
    unsigned wall;
} SpaceWall;

static bool space_runs_meet(const void *ctx, uint32_t lo, uint32_t hi)
{
    const SpaceWall *w = ctx;
    for (uint32_t x = lo; x <= hi; x++)
        if (!has(w->cells, w->first_vertex + x, w->wall))
            return true;
    return false;
}

static bool space_runs_build(const Collapse *c, SgRowRuns *r)
{
    const SgComplex *cx = c->cx;
    size_t row_length = (size_t)cx->lx - 1, rows_y = space_rows_y(c);
    if (!sg_row_runs_begin(r, rows_y * ((size_t)cx->lz - 1)))
        return false;
    for (size_t row = 0; row < r->rows; row++) {
        sg_row_runs_start_row(r, row);
        size_t y = row % rows_y, z = row / rows_y;
        const uint8_t *cells = c->cells + y * c->st[1] + z * c->st[2];
        uint32_t x0 = 0;
        for (uint32_t x = 1; x < row_length; x++)
            if (cells[x] >> 6 & 1) { /* the yz square at x walls x-1 off from x */
                if (!sg_row_runs_push(r, x0, x - 1))
                    return false;
                x0 = x;
            }
        if (!sg_row_runs_push(r, x0, (uint32_t)row_length - 1))
            return false;
    }
    if (!sg_row_runs_end(r))
        return false;
    for (size_t row = 0; row < r->rows; row++) {
        size_t y = row % rows_y, z = row / rows_y;
        size_t first = y * c->st[1] + z * c->st[2];
        if (y > 0) /* xz square */
            sg_row_runs_connect(r, row - 1, row, 0, space_runs_meet, &(SpaceWall){c->cells, first, 5});
        if (z > 0) /* xy square */
            sg_row_runs_connect(r, row - rows_y, row, 0, space_runs_meet, &(SpaceWall){c->cells, first, 3});
    }
    return true;
}

/* The region (root run) of lattice vertex v. */
static uint32_t space_region(const Collapse *c, SgRowRuns *r, size_t v)
{
    size_t x = v % c->st[1], y = v / c->st[1] % ((size_t)c->cx->ly), z = v / c->st[2];
    return sg_set_find(r->parent, sg_row_runs_at(r, y + space_rows_y(c) * z, (uint32_t)x));
}

/* The collapse is stuck with squares left: no free face anywhere. The
 * squares left bound regions of space; a square with different regions on
 * its two sides lies on a closed surface (a 2-cycle), and removing it
 * merges the two regions: b2 drops by one and b1 is unchanged (removing a
 * 2-cell changes chi by one, and b0 does not move). Squares are tried from
 * the thinnest air outwards and a union-find over regions picks one per
 * cavity. If no square separates two regions (a stuck contractible 2D
 * part, in theory possible), one square is removed anyway and counted as a
 * forced break, which adds a loop. */
static bool break_cavities(Collapse *c)
{
    Sink sink = {c->cur, c->next, &c->live, false};
    SgComplex *cx = c->cx;
    U32Vec squares = {0};
    for (size_t v = 0; v < cx->vertex_count; v++) {
        unsigned bits = c->cells[v] & SQUARE_BITS;
        for (unsigned m = 3; bits && m <= 6; m++)
            if (bits >> m & 1)
                u32_push(c, &squares, (uint32_t)(v * 8 + m));
    }
    size_t n = squares.n;
    uint32_t *side = malloc(2 * n * sizeof *side + 1);
    uint64_t *order = malloc(n * sizeof *order + 1);
    SgRowRuns runs;
    bool ok = false;
    bool built = space_runs_build(c, &runs);
    if (c->oom || !side || !order || !built)
        goto done;
    /* side 0: the vertex below the square along its normal; side 1: above */
    for (size_t i = 0; i < n; i++) {
        size_t w = squares.a[i] >> 3;
        unsigned normal = 7u ^ (squares.a[i] & 7);
        int a = normal == 1 ? 0 : normal == 2 ? 1 : 2;
        side[2 * i] = space_region(c, &runs, w - c->st[a]);
        side[2 * i + 1] = space_region(c, &runs, w);
    }
    /* the regions' own union-find, over root run ids */
    for (size_t i = 0; i < runs.count; i++)
        runs.parent[i] = (uint32_t)i;
    for (size_t i = 0; i < n; i++) {
        size_t w = squares.a[i] >> 3;
        unsigned normal = 7u ^ (squares.a[i] & 7);
        int a = normal == 1 ? 0 : normal == 2 ? 1 : 2;
        uint64_t thin = (uint64_t)voxel_dist8(c, w) + voxel_dist8(c, w - c->st[a]);
        order[i] = thin << 32 | (uint64_t)i;
    }
    qsort(order, n, sizeof *order, compare_u64);
    c->substep = KINDS - 1; /* everything freed now waits for the next step */
    uint32_t broken = 0;
    for (size_t j = 0; j < n; j++) {
        size_t i = (size_t)(order[j] & 0xffffffffu);
        if (!sg_set_union(runs.parent, side[2 * i], side[2 * i + 1]))
            continue;
        remove_cell(c, squares.a[i]);
        c->squares--;
        c->removed++;
        broken++;
        note_isolated_edges(c, &sink, squares.a[i]);
        consider_faces(c, &sink, squares.a[i]);
    }
    c->cavities_broken_total += broken;
    if (broken == 0 && n > 0) {
        size_t i = (size_t)(order[0] & 0xffffffffu);
        remove_cell(c, squares.a[i]);
        c->squares--;
        c->removed++;
        c->forced_total++;
        note_isolated_edges(c, &sink, squares.a[i]);
        consider_faces(c, &sink, squares.a[i]);
    }
    ok = !c->oom && !sink.oom;
done:
    free(squares.a);
    free(side);
    free(order);
    sg_row_runs_release(&runs);
    if (!ok)
        c->oom = true;
    return ok;
}

/* ---- driver ------------------------------------------------------------ */

static bool interior_vertex(const Collapse *c, size_t v)
{
    /* all 8 voxels around v present: every cell of v has two cofaces per axis */
    const uint8_t *cells = c->cells;
    for (unsigned d = 0; d < 8; d++) {
        size_t w = v - ((d & 1) ? c->st[0] : 0) - ((d & 2) ? c->st[1] : 0) -
                   ((d & 4) ? c->st[2] : 0);
        if (!(cells[w] & 0x80))
            return false;
    }
    return true;
}

static int popcount8(unsigned x)
{
    int n = 0;
    for (; x; x &= x - 1)
        n++;
    return n;
}

bool sg_collapse(SgComplex *cx, const uint32_t *constrained, size_t constrained_count,
                 const uint16_t *dist8, const uint16_t *open8, double filter_scale,
                 int threads, uint32_t parallel_grain, SgProgress *progress,
                 SgCollapseResult *result, SgError *err)
{
    memset(result, 0, sizeof *result);
    Helper helpers[MAX_THREADS];
    pthread_t ids[MAX_THREADS];
    int started = 0;
    Collapse c = {.cx = cx, .cells = cx->cells, .dist8 = dist8, .open8 = open8};
    pthread_mutex_init(&c.gate_lock, NULL);
    pthread_cond_init(&c.gate, NULL);
    atomic_init(&c.next_slab, 0);
    /* the rule compares 8 x lifespan with scale x (8 x opening): in 1/256 */
    c.filter256 = filter_scale >= 0 && filter_scale < 1e6 ? (int64_t)(filter_scale * 256 + 0.5) : 256;
    for (int a = 0; a < 3; a++)
        c.st[a] = cx->stride[a];
    c.cur = c.queue_a;
    c.next = c.queue_b;
    c.cell_limit = (uint64_t)cx->vertex_count * 8;
    bool ok = false;
    if (!cell_set_init(&c.cons)) {
        c.oom = true;
        goto done;
    }
    for (size_t i = 0; i < constrained_count; i++)
        if (!cell_set_add(&c.cons, constrained[i])) {
            c.oom = true;
            goto done;
        }

    /* worker threads for large sub-steps: slabs of at least SLAB_MIN
     * planes, about 8 per thread for balance */
    c.parallel_grain = parallel_grain;
    c.threads = parallel_grain ? sg_thread_count(threads) : 1;
    if (c.threads > MAX_THREADS)
        c.threads = MAX_THREADS;
    c.slab_planes = (size_t)cx->lz / (8 * (size_t)c.threads);
    if (c.slab_planes < SLAB_MIN)
        c.slab_planes = SLAB_MIN;
    c.slab_count = ((size_t)cx->lz + c.slab_planes - 1) / c.slab_planes;
    if (c.slab_count < 4)
        c.threads = 1; /* too thin to split */
    if (c.threads > 1) {
        c.workers = calloc((size_t)c.threads, sizeof *c.workers);
        c.slab_start = calloc(c.slab_count + 1, sizeof *c.slab_start);
        if (!c.workers || !c.slab_start) {
            c.oom = true;
            goto done;
        }
        for (int t = 0; t < c.threads; t++) {
            Worker *w = &c.workers[t];
            w->sink = (Sink){w->cur, w->next, &w->noted, false};
        }
        /* helpers wait at the gate until the barriers are sized to the
         * threads that really started */
        for (int t = 1; t < c.threads; t++) {
            helpers[t] = (Helper){&c, t};
            if (pthread_create(&ids[t], NULL, helper_main, &helpers[t]) != 0)
                break;
            started = t;
        }
        c.threads = started + 1;
        if (started > 0) {
            pthread_barrier_init(&c.start, NULL, (unsigned)c.threads);
            pthread_barrier_init(&c.end, NULL, (unsigned)c.threads);
        }
        pthread_mutex_lock(&c.gate_lock);
        c.gate_open = true;
        pthread_cond_broadcast(&c.gate);
        pthread_mutex_unlock(&c.gate_lock);
    }

    /* the first free faces: only vertices next to the outside of the medium */
    c.substep = KINDS - 1;
    Sink sink = {c.cur, c.next, &c.live, false};
    for (int z = 0; z <= cx->nz; z++) {
        for (int y = 0; y <= cx->ny; y++) {
            size_t v = sg_complex_vertex(cx, 0, y, z);
            for (int x = 0; x <= cx->nx; x++, v++) {
                unsigned bits = c.cells[v];
                if (!bits)
                    continue;
                c.total += (uint64_t)popcount8(bits);
                c.squares += (uint64_t)popcount8(bits & SQUARE_BITS);
                if (interior_vertex(&c, v))
                    continue;
                for (unsigned m = 0; m < 7; m++)
                    if (bits >> m & 1)
                        consider(&c, &sink, (uint32_t)(v * 8 + m));
            }
        }
        if (c.oom || sink.oom) {
            c.oom = true;
            goto done;
        }
    }

    if (progress)
        progress->total = c.total; /* cells removed / cells at the start */
    for (;;) {
        bool any = false;
        for (int k = 0; k < KINDS; k++)
            any |= c.next[k].n > 0;
        if (!any) {
            if (c.squares == 0)
                break;
            if (!break_cavities(&c))
                goto done;
            continue;
        }
        c.step++;
        U32Vec *t = c.cur;
        c.cur = c.next;
        c.next = t;
        for (int s = 0; s < KINDS && !c.oom; s++)
            run_substep(&c, s);
        if (c.oom)
            goto done;
        apply_lifespan_rule(&c);
        if (c.oom)
            goto done;
        if (progress)
            sg_progress_update(progress, c.removed);
    }

    /* every surviving edge: kept ones and live ones still present */
    size_t total = c.kept.n + c.live.n;
    result->edges = malloc((total ? total : 1) * sizeof *result->edges);
    if (!result->edges) {
        c.oom = true;
        goto done;
    }
    size_t w = 0;
    for (size_t i = 0; i < c.kept.n; i++)
        result->edges[w++] = c.kept.a[i];
    for (size_t i = 0; i < c.live.n; i++)
        if (has(c.cells, c.live.a[i].cell >> 3, c.live.a[i].cell & 7))
            result->edges[w++] = c.live.a[i];
    qsort(result->edges, w, sizeof *result->edges, compare_edge_cell);
    result->edge_count = w;
    for (size_t i = 1; i < w; i++)
        if (result->edges[i].cell == result->edges[i - 1].cell) {
            sg_fail(err, "collapse: internal error: edge noted twice");
            c.oom = true;
            goto done;
        }
    result->steps = (uint32_t)c.step;
    result->cavities_broken = c.cavities_broken_total;
    result->forced_breaks = c.forced_total;
    ok = true;
done:
    if (started > 0) {
        c.job = JOB_EXIT;
        pthread_barrier_wait(&c.start);
        for (int t = 1; t <= started; t++)
            pthread_join(ids[t], NULL);
        pthread_barrier_destroy(&c.start);
        pthread_barrier_destroy(&c.end);
    }
    pthread_mutex_destroy(&c.gate_lock);
    pthread_cond_destroy(&c.gate);
    if (c.workers) {
        for (int t = 0; t < c.threads; t++) {
            Worker *wk = &c.workers[t];
            free(wk->pairs.a);
            for (int k = 0; k < KINDS; k++) {
                free(wk->cur[k].a);
                free(wk->next[k].a);
            }
            free(wk->noted.a);
        }
    }
    free(c.workers);
    free(c.slab_start);
    for (int k = 0; k < KINDS; k++) {
        free(c.queue_a[k].a);
        free(c.queue_b[k].a);
    }
    free(c.pairs.a);
    free(c.sort_scratch.a);
    free(c.live.a);
    free(c.kept.a);
    free(c.cons.slot);
    if (!ok) {
        sg_collapse_result_release(result);
        return sg_fail(err, "collapse: out of memory");
    }
    return true;
}

void sg_collapse_result_release(SgCollapseResult *r)
{
    if (!r)
        return;
    free(r->edges);
    memset(r, 0, sizeof *r);
}
