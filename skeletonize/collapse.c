/* Directional parallel collapse [CC09], 1D variant with the lifespan /
 * opening rule [Cha10].
 *
 * A step runs 18 sub-steps: direction x, y, z; orientation +, -; coface
 * dimension 3, 2, 1. Sub-step s removes, at once, every free pair of its
 * kind that was free when it began (CC09: such pairs cannot interfere).
 * Free faces wait in queues (flat uint32 arrays of cell ids); a face is
 * queued when it becomes free, which can only happen when one of its
 * cofaces is removed, so after a removal only the faces of the removed
 * cells are re-tested: each step costs the size of the current border.
 * A face is queued when, right after one of its cofaces goes, it has
 * exactly one coface left (or at the start). Cofaces only ever go, so that
 * count passes 1 once: a cell is queued at most once, with no need for a
 * "queued" bit per cell. A queued face may stop being free (its coface
 * goes with another face): it is checked again when its sub-step comes.
 *
 * Temporal blocking: the lattice is cut into slabs of z planes, each with
 * its own queues, and a step runs its 18 sub-steps slab by slab along a
 * wavefront rather than each over the whole lattice: sub-step s of slab i
 * comes after sub-step s - 1 of slabs i - 1, i, i + 1 and before sub-step
 * s + 1 of slabs i - 1 and i + 1. The work for a pair whose face lies in
 * plane z reads planes z - 2 .. z + 1 and writes z - 1 .. z only, so with
 * slabs of two planes or more every cell sees the sub-steps around it in
 * their order (those of one sub-step in some order, which does not change
 * which pairs it removes: they cannot interfere), and the collapse removes
 * the same pairs at the same sub-steps as one sweep of the lattice per
 * sub-step. What it gains: the 18 sub-steps of a step pass over a band of
 * slabs while its border is in cache, where each used to sweep the border
 * of the whole lattice (a step's border at resolution 1000 does not fit).
 *
 * Threads: slabs two apart touch disjoint planes, so threads take the
 * ready (slab, sub-step) of lowest wave whose neighbouring slabs are idle;
 * a slab's queues are filled by itself, the slab below and the slab above
 * into three separate sets, so no two running slabs push into the same
 * array. No barrier per sub-step: a thread waits only when no slab is
 * ready, and the threads meet once a step. The result does not depend on
 * the threads. */
#include "collapse.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "row_runs.h"
#include "threads.h"
#include "union_find.h"

#define KINDS 18
#define SQUARE_BITS 0x68u /* masks 3, 5, 6 */

typedef struct U32Vec {
    uint32_t *a;
    size_t n, cap;
} U32Vec;

typedef struct EdgeVec {
    SgIsolatedEdge *a;
    size_t n, cap;
} EdgeVec;

/* A slab's queues fill from three sources: the slab's own sub-steps (and
 * the set-up, the cavity breaks), the slab below, the slab above. */
#define SOURCE_OWN 0
#define SOURCE_BELOW 1
#define SOURCE_ABOVE 2
#define SOURCES 3

typedef struct SlabQueues {
    U32Vec q[SOURCES][2][KINDS]; /* [source][step parity][kind] */
} SlabQueues;

#define NO_SLAB SIZE_MAX
/* A slab's queue for one kind holds a few hundred faces a step; the larger
 * ones (the whole border at the start) are freed once used. */
#define QUEUE_KEEP 4096

/* What one thread's work on a (slab, sub-step) writes besides the cells:
 * the pairs it found, the edges it saw isolated, its counts. */
typedef struct Sink {
    int substep;       /* the running sub-step (the set-up, cavity breaks: the last) */
    /* where consider() queues a face: the queues of the running slab, of
     * the one below (cells below `first`), of the one above (from `end`),
     * each [parity][kind], at slot[kind] (this step or the next) */
    uint64_t first, end;
    U32Vec *own, *lower, *upper;
    uint8_t slot[KINDS];
    U32Vec pairs;      /* f, g, f, g, ... */
    EdgeVec *noted;
    EdgeVec own_noted; /* a helper thread's, merged after the step */
    uint64_t removed, squares_removed;
    bool oom;
} Sink;

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

typedef struct Collapse Collapse;
typedef struct Helper {
    Collapse *c;
    int t;
} Helper;

#define MAX_THREADS 8
/* Slabs hold two planes at least (see the header), and by default two:
 * the band of slabs a step's wavefront spans (18 slabs) is then the
 * thinnest, the most likely to stay in cache (Sponza 250 under cachegrind
 * with a 1 MB last level: 11.2 M misses with slabs of 2 planes, 12.9 M
 * with slabs of 8). */
#define SLAB_MIN_PLANES 2

struct Collapse {
    SgComplex *cx;
    uint8_t *cells;
    CellSet cons;       /* the constraint set: lights, camera, kept edges */
    size_t st[3];
    int cur_side;       /* the step's queues: q[cur_side]; the next step's: q[!cur_side] */
    size_t slab_planes, slab_count;
    uint64_t slab_cells; /* cell ids per slab */
    SlabQueues *slabs;
    SlabQueues staged;  /* the set-up's and the cavity breaks' faces, not yet in their slabs */
    EdgeVec live;       /* isolated edges noted since the last step's end */
    EdgeVec *due;       /* due[l]: edges that join the constraint set at the end of
                           step l if still there (the lifespan rule, see below) */
    size_t due_count;
    EdgeVec far;        /* edges due more than DUE_MOST steps ahead: the rule is
                           tested on them every step */
    EdgeVec kept;       /* isolated edges in the constraint set */
    const uint16_t *dist8, *open8; /* lattice layout: voxel at its lower corner */
    int32_t step;
    uint64_t squares, removed, total;
    uint32_t cavities_broken_total, forced_total;
    int64_t filter256;
    bool oom;
    /* threads: the wavefront's state, under `lock` */
    int threads;
    Sink *sinks;        /* one per thread */
    pthread_mutex_t lock;
    pthread_cond_t changed;
    uint8_t *done;      /* sub-steps done, per slab, this step */
    uint8_t *busy;      /* a thread works on the slab */
    uint64_t *slab_work; /* faces queued per slab at the step's start */
    uint64_t schedule_state; /* tests: != 0, the shuffled schedule's random state */
    bool stuck;         /* the shuffled schedule found nothing ready */
    size_t lowest;      /* slabs below have done the step */
    size_t region_lo[MAX_THREADS], region_hi[MAX_THREADS]; /* each thread's slabs this step */
    size_t remaining;   /* (slab, sub-step)s not yet done this step */
    bool exit;
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

/* Queues face h if it is free: for the kind's sub-step this step if that
 * is still to come, else next step; in the queues of h's slab (the running
 * slab or one next to it), the set the running slab fills. */
static inline __attribute__((always_inline)) void consider(const Collapse *c, Sink *sk,
                                                           uint32_t h)
{
    uint32_t g;
    int k = free_kind(c, h, &g);
    if (k < 0)
        return;
    U32Vec *queues = h < sk->first ? sk->lower : h >= sk->end ? sk->upper : sk->own;
    if (!vec_push_u32(&queues[sk->slot[k]], h))
        sk->oom = true;
}

/* Points sk at slab i's sub-step s (NO_SLAB: c->staged, for the next step). */
static void sink_aim(Collapse *c, Sink *sk, size_t i, int s)
{
    sk->substep = s;
    for (int k = 0; k < KINDS; k++)
        sk->slot[k] = (uint8_t)((k > s ? c->cur_side : !c->cur_side) * KINDS + k);
    if (i == NO_SLAB) {
        sk->first = 0;
        sk->end = UINT64_MAX;
        sk->own = sk->lower = sk->upper = &c->staged.q[SOURCE_OWN][0][0];
        return;
    }
    sk->first = (uint64_t)i * c->slab_cells;
    sk->end = sk->first + c->slab_cells;
    sk->own = &c->slabs[i].q[SOURCE_OWN][0][0];
    sk->lower = i > 0 ? &c->slabs[i - 1].q[SOURCE_ABOVE][0][0] : NULL;
    sk->upper = i + 1 < c->slab_count ? &c->slabs[i + 1].q[SOURCE_BELOW][0][0] : NULL;
}

/* Hands the faces queued by the set-up or a cavity break (next step's, in
 * c->staged) to their slabs. */
static void distribute_staged(Collapse *c)
{
    int side = !c->cur_side;
    for (int k = 0; k < KINDS && !c->oom; k++) {
        U32Vec *q = &c->staged.q[SOURCE_OWN][side][k];
        for (size_t x = 0; x < q->n; x++) {
            uint32_t h = q->a[x];
            u32_push(c, &c->slabs[h / c->slab_cells].q[SOURCE_OWN][side][k], h);
        }
        free(q->a);
        *q = (U32Vec){0};
    }
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

/* An isolated edge's opening is looked up when the lifespan rule first
 * needs it, at the end of the step it was born in: most such edges are
 * gone by then (removed with a free vertex), and the lookup was a cache
 * miss on the opening map, the largest part of noting an edge. */
#define OPENING_UNKNOWN UINT16_MAX

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
        SgIsolatedEdge noted = {edges[i], c->step, -1, OPENING_UNKNOWN};
        if (!vec_push_edge(sk->noted, noted))
            sk->oom = true;
    }
}

static void remove_cell(const Collapse *c, uint32_t cell)
{
    c->cells[cell >> 3] &= (uint8_t) ~(1u << (cell & 7));
}


/* Removes the sink's pairs one by one, noting isolated edges and queueing
 * newly free faces. The pairs were all tested against the complex as the
 * sub-step found it, so removing them in any order gives the same
 * complex; noting an edge right after each square goes notes it exactly
 * once (when its last square goes); a face tested too early is tested
 * again when its other coface goes. */
static void process_pairs(const Collapse *c, Sink *sk)
{
    int coface_dim = 3 - sk->substep % 3;
    const uint32_t *pairs = sk->pairs.a;
    size_t n = sk->pairs.n / 2;
    for (size_t i = 0; i < n; i++) {
        uint32_t f = pairs[2 * i], g = pairs[2 * i + 1];
        remove_cell(c, f);
        remove_cell(c, g);
        /* coface_dim 3: each edge of the square f is also an edge of
         * another square of the cube g, still here: none becomes isolated */
        if (coface_dim == 2)
            note_isolated_edges(c, sk, g);
        consider_faces(c, sk, g);
        consider_faces(c, sk, f);
    }
    sk->removed += 2 * n;
    if (coface_dim >= 2)
        sk->squares_removed += n;
}

static bool slab_has_work(const Collapse *c, size_t i, int s)
{
    const SlabQueues *sq = &c->slabs[i];
    for (int source = 0; source < SOURCES; source++)
        if (sq->q[source][c->cur_side][s].n)
            return true;
    return false;
}

/* Sub-step s of slab i: verify its queued faces against the complex (the
 * pairs still free of kind s), then remove them. */
static void run_slab_substep(Collapse *c, Sink *sk, size_t i, int s)
{
    sink_aim(c, sk, i, s);
    sk->pairs.n = 0;
    SlabQueues *sq = &c->slabs[i];
    for (int source = 0; source < SOURCES; source++) {
        U32Vec *q = &sq->q[source][c->cur_side][s];
        for (size_t x = 0; x < q->n; x++) {
            uint32_t f = q->a[x], g = 0;
            if (free_kind(c, f, &g) == s &&
                (!vec_push_u32(&sk->pairs, f) || !vec_push_u32(&sk->pairs, g)))
                sk->oom = true;
        }
        q->n = 0;
        if (q->cap > QUEUE_KEEP) { /* the set-up's surge: do not keep it in every slab */
            free(q->a);
            *q = (U32Vec){0};
        }
    }
    if (!sk->oom)
        process_pairs(c, sk);
}

/* One step on one thread: waves w = slab + sub-step upwards, each from
 * its lowest sub-step (sub-step s of slab i after s - 1 of slab i + 1). */
static void run_step_serial(Collapse *c)
{
    Sink *sk = &c->sinks[0];
    for (size_t w = 0; w < c->slab_count + KINDS - 1 && !sk->oom; w++)
        for (int s = 0; s < KINDS && (size_t)s <= w; s++) {
            size_t i = w - (size_t)s;
            if (i < c->slab_count && slab_has_work(c, i, s))
                run_slab_substep(c, sk, i, s);
        }
}

/* ---- threads ----------------------------------------------------------- */

/* Slab i may run its next sub-step s when its neighbours are idle, have
 * done s - 1 and have not done s + 1. */
static bool slab_ready(const Collapse *c, size_t i)
{
    int s = c->done[i];
    if (s >= KINDS || c->busy[i])
        return false;
    if (i > 0 && (c->busy[i - 1] || c->done[i - 1] < s || c->done[i - 1] > s + 1))
        return false;
    if (i + 1 < c->slab_count && (c->busy[i + 1] || c->done[i + 1] < s || c->done[i + 1] > s + 1))
        return false;
    return true;
}

/* The ready slab of lowest wave (slab + sub-step) in [lo, hi), NO_SLAB if
 * none. Under the lock. */
static size_t lowest_wave_ready(const Collapse *c, size_t lo, size_t hi)
{
    size_t best = NO_SLAB, best_wave = SIZE_MAX;
    for (size_t i = lo; i < hi && i <= best_wave; i++) {
        if (!slab_ready(c, i))
            continue;
        size_t wave = i + c->done[i];
        if (wave < best_wave) {
            best = i;
            best_wave = wave;
        }
    }
    return best;
}

/* Under the lock: thread t's next (slab, sub-step): the ready slab of
 * lowest wave in its own region, as the serial order runs them, else in
 * any; sub-steps with nothing queued are done on the spot. NO_SLAB: none
 * ready. */
static size_t pick_slab(Collapse *c, int t)
{
    for (;;) {
        while (c->lowest < c->slab_count && c->done[c->lowest] == KINDS)
            c->lowest++;
        size_t lo = c->region_lo[t] > c->lowest ? c->region_lo[t] : c->lowest;
        size_t best = lowest_wave_ready(c, lo, c->region_hi[t]);
        if (best == NO_SLAB)
            best = lowest_wave_ready(c, c->lowest, c->slab_count);
        if (best == NO_SLAB || slab_has_work(c, best, c->done[best]))
            return best;
        c->done[best]++;
        c->remaining--;
    }
}

/* Each thread's region this step: contiguous slabs holding about an equal
 * share of the faces queued at the step's start. A thread keeps to its
 * region while it has a ready slab there, so a slab's sub-steps mostly
 * run on one core and its lines stay in that core's cache; it helps
 * elsewhere when it has none. */
static void split_regions(Collapse *c)
{
    uint64_t total = 0;
    uint64_t *work = c->slab_work;
    for (size_t i = 0; i < c->slab_count; i++) {
        uint64_t n = 0;
        for (int source = 0; source < SOURCES; source++)
            for (int k = 0; k < KINDS; k++)
                n += c->slabs[i].q[source][c->cur_side][k].n;
        work[i] = n;
        total += n;
    }
    size_t i = 0;
    uint64_t sum = 0;
    for (int t = 0; t < c->threads; t++) {
        c->region_lo[t] = i;
        uint64_t target = total * (uint64_t)(t + 1) / (uint64_t)c->threads;
        while (i < c->slab_count && (t + 1 == c->threads || sum + work[i] / 2 < target))
            sum += work[i++];
        c->region_hi[t] = i;
    }
}

/* Thread t's share of a step: runs ready slabs until the step is done
 * (t = 0, the caller) or the collapse ends (helpers). Under the lock. */
static void work_on_steps(Collapse *c, int t)
{
    Sink *sk = &c->sinks[t];
    for (;;) {
        if (c->exit || (t == 0 && c->remaining == 0))
            return;
        size_t i = pick_slab(c, t);
        if (i == NO_SLAB) {
            if (t == 0 && c->remaining == 0)
                return;
            pthread_cond_wait(&c->changed, &c->lock);
            continue;
        }
        int s = c->done[i];
        c->busy[i] = 1;
        pthread_mutex_unlock(&c->lock);
        run_slab_substep(c, sk, i, s);
        pthread_mutex_lock(&c->lock);
        c->busy[i] = 0;
        c->done[i]++;
        c->remaining--;
        pthread_cond_broadcast(&c->changed);
    }
}

static void *helper_main(void *arg)
{
    Helper *h = arg;
    Collapse *c = h->c;
    pthread_mutex_lock(&c->lock);
    work_on_steps(c, h->t);
    pthread_mutex_unlock(&c->lock);
    return NULL;
}

static void run_step_parallel(Collapse *c)
{
    pthread_mutex_lock(&c->lock);
    memset(c->done, 0, c->slab_count);
    c->lowest = 0;
    c->remaining = c->slab_count * KINDS;
    split_regions(c);
    pthread_cond_broadcast(&c->changed);
    work_on_steps(c, 0);
    pthread_mutex_unlock(&c->lock);
}

/* The tests' schedule: one thread plays two, each taking a random ready
 * (slab, sub-step) when free, the two finishing in a random order; no
 * empty sub-step skipped. Any order the readiness rule allows must give
 * the same complex, so a fault in the rule shows as a different skeleton
 * on one thread, reproducibly. */
static uint64_t schedule_random(Collapse *c)
{
    uint64_t x = c->schedule_state; /* xorshift64 */
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return c->schedule_state = x;
}

static void run_step_shuffled(Collapse *c)
{
    Sink *sk = &c->sinks[0];
    uint64_t *ready = c->slab_work; /* free during a step */
    size_t flight[2];
    int flight_substep[2], n = 0;
    memset(c->done, 0, c->slab_count);
    for (size_t remaining = c->slab_count * KINDS; remaining > 0 && !sk->oom; remaining--) {
        while (n < 2) {
            size_t count = 0;
            for (size_t i = 0; i < c->slab_count; i++)
                if (slab_ready(c, i))
                    ready[count++] = i;
            if (count == 0)
                break;
            size_t i = (size_t)ready[schedule_random(c) % count];
            c->busy[i] = 1;
            flight[n] = i;
            flight_substep[n++] = c->done[i];
        }
        if (n == 0) { /* the rule left nothing ready: a fault, not a schedule */
            c->stuck = true;
            return;
        }
        int j = n == 2 ? (int)(schedule_random(c) & 1) : 0;
        run_slab_substep(c, sk, flight[j], flight_substep[j]);
        c->busy[flight[j]] = 0;
        c->done[flight[j]]++;
        n--;
        flight[j] = flight[n];
        flight_substep[j] = flight_substep[n];
    }
}

/* Runs step c->step (its queues on c->cur_side), then gathers what the
 * threads found. */
static void run_step(Collapse *c)
{
    if (c->schedule_state)
        run_step_shuffled(c);
    else if (c->threads > 1)
        run_step_parallel(c);
    else
        run_step_serial(c);
    for (int t = 0; t < c->threads; t++) {
        Sink *sk = &c->sinks[t];
        c->oom |= sk->oom;
        c->removed += sk->removed;
        c->squares -= sk->squares_removed;
        sk->removed = sk->squares_removed = 0;
        for (size_t i = 0; t > 0 && i < sk->own_noted.n; i++)
            edge_push(c, &c->live, sk->own_noted.a[i]);
        sk->own_noted.n = 0;
    }
}

static int compare_edge_cell(const void *a, const void *b)
{
    uint32_t x = ((const SgIsolatedEdge *)a)->cell, y = ((const SgIsolatedEdge *)b)->cell;
    return (x > y) - (x < y);
}

/* After step l: an isolated edge with l - birth(e) > opening(e) is kept.
 * Both sides are known once the edge's opening is (at the end of the step
 * that noted it), so the step l at which it will be kept, if it is still
 * there, is too: it waits in due[l] instead of being tested every step
 * (at Sponza 1000 the live edges' scan every step was 2-3% of the step,
 * serial). */
#define DUE_MOST 65536

/* The first step l with (l - birth) x 8 x 256 > open8 x filter256. */
static int64_t keep_step(const Collapse *c, const SgIsolatedEdge *e)
{
    return (int64_t)e->birth + (int64_t)e->open8 * c->filter256 / 2048 + 1;
}

static void keep_edge(Collapse *c, SgIsolatedEdge e)
{
    if (!cell_set_add(&c->cons, e.cell))
        c->oom = true;
    e.kept = c->step;
    edge_push(c, &c->kept, e);
}

static void wait_until(Collapse *c, SgIsolatedEdge e, int64_t l)
{
    if (l >= (int64_t)c->due_count) {
        size_t count = c->due_count * 2 > (size_t)l + 1 ? c->due_count * 2 : (size_t)l + 64;
        EdgeVec *grown = realloc(c->due, count * sizeof *grown);
        if (!grown) {
            c->oom = true;
            return;
        }
        memset(grown + c->due_count, 0, (count - c->due_count) * sizeof *grown);
        c->due = grown;
        c->due_count = count;
    }
    edge_push(c, &c->due[l], e);
}

static void apply_lifespan_rule(Collapse *c)
{
    for (size_t i = 0; i < c->live.n; i++) { /* newly isolated: when they are due */
        SgIsolatedEdge e = c->live.a[i];
        size_t v = e.cell >> 3;
        unsigned m = e.cell & 7;
        if (!has(c->cells, v, m))
            continue;
        if (e.open8 == OPENING_UNKNOWN)
            e.open8 = edge_opening(c, v, m);
        int64_t l = keep_step(c, &e);
        if (l <= c->step)
            keep_edge(c, e);
        else if (l - c->step > DUE_MOST)
            edge_push(c, &c->far, e);
        else
            wait_until(c, e, l);
    }
    c->live.n = 0;
    if ((size_t)c->step < c->due_count) { /* due now */
        EdgeVec *now = &c->due[c->step];
        for (size_t i = 0; i < now->n; i++)
            if (has(c->cells, now->a[i].cell >> 3, now->a[i].cell & 7))
                keep_edge(c, now->a[i]);
        free(now->a);
        *now = (EdgeVec){0};
    }
    size_t w = 0;
    for (size_t i = 0; i < c->far.n; i++) {
        SgIsolatedEdge e = c->far.a[i];
        if (!has(c->cells, e.cell >> 3, e.cell & 7))
            continue;
        if (keep_step(c, &e) <= c->step)
            keep_edge(c, e);
        else
            c->far.a[w++] = e;
    }
    c->far.n = w;
}

/* Appends the edges of v still in the complex to out at *w. */
static void gather_present(const Collapse *c, const EdgeVec *v, SgIsolatedEdge *out, size_t *w)
{
    for (size_t i = 0; i < v->n; i++) {
        SgIsolatedEdge e = v->a[i];
        if (!has(c->cells, e.cell >> 3, e.cell & 7))
            continue;
        if (e.open8 == OPENING_UNKNOWN) /* noted by the last cavity break */
            e.open8 = edge_opening(c, e.cell >> 3, e.cell & 7);
        out[(*w)++] = e;
    }
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
    Sink *sink = &c->sinks[0];
    sink_aim(c, sink, NO_SLAB, KINDS - 1); /* everything freed now waits for the next step */
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
    uint32_t broken = 0;
    for (size_t j = 0; j < n; j++) {
        size_t i = (size_t)(order[j] & 0xffffffffu);
        if (!sg_set_union(runs.parent, side[2 * i], side[2 * i + 1]))
            continue;
        remove_cell(c, squares.a[i]);
        c->squares--;
        c->removed++;
        broken++;
        note_isolated_edges(c, sink, squares.a[i]);
        consider_faces(c, sink, squares.a[i]);
    }
    c->cavities_broken_total += broken;
    if (broken == 0 && n > 0) {
        size_t i = (size_t)(order[0] & 0xffffffffu);
        remove_cell(c, squares.a[i]);
        c->squares--;
        c->removed++;
        c->forced_total++;
        note_isolated_edges(c, sink, squares.a[i]);
        consider_faces(c, sink, squares.a[i]);
    }
    distribute_staged(c);
    ok = !c->oom && !sink->oom;
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

/* The collapse's set-up, a slab per task: counts and queues the first
 * free faces, those of vertices next to the outside of the medium. A
 * face's queue is its vertex's slab's, filled by that slab's task alone in
 * the order one thread would (planes, rows, vertices upwards). */
typedef struct SetupCount {
    uint64_t total, squares; /* the slab's cells, its squares */
    bool oom;
} SetupCount;

typedef struct SetupPass {
    Collapse *c;
    SetupCount *slab; /* per slab */
} SetupPass;

static void setup_slab(void *ctx, uint64_t i, int thread)
{
    (void)thread;
    Collapse *c = ((SetupPass *)ctx)->c;
    SetupCount *count = &((SetupPass *)ctx)->slab[i];
    Sink sk;
    memset(&sk, 0, sizeof sk);
    sink_aim(c, &sk, (size_t)i, KINDS - 1); /* for the first step */
    /* vertex z (grid coordinates) is lattice plane z + 1 */
    long lo = (long)(i * c->slab_planes) - 1, hi = (long)((i + 1) * c->slab_planes) - 1;
    for (long z = lo < 0 ? 0 : lo; z < hi && z <= c->cx->nz; z++)
        for (int y = 0; y <= c->cx->ny; y++) {
            size_t v = sg_complex_vertex(c->cx, 0, y, (int)z);
            for (int x = 0; x <= c->cx->nx; x++, v++) {
                unsigned bits = c->cells[v];
                if (!bits)
                    continue;
                count->total += (uint64_t)popcount8(bits);
                count->squares += (uint64_t)popcount8(bits & SQUARE_BITS);
                if (interior_vertex(c, v))
                    continue;
                for (unsigned m = 0; m < 7; m++)
                    if (bits >> m & 1)
                        consider(c, &sk, (uint32_t)(v * 8 + m));
            }
        }
    count->oom = sk.oom;
}

/* The constrained cells, which the collapse never removes. */
static bool collapse_set_constraints(Collapse *c, const uint32_t *constrained, size_t constrained_count)
{
    if (!cell_set_init(&c->cons))
        return false;
    for (size_t i = 0; i < constrained_count; i++)
        if (!cell_set_add(&c->cons, constrained[i]))
            return false;
    return true;
}

/* Slabs of z planes (SLAB_MIN_PLANES unless told, no more than the
 * lattice), the threads that work on them, and their queues. */
static bool collapse_plan_slabs(Collapse *c, int threads, uint32_t parallel_grain, uint32_t slab_planes,
                                uint64_t schedule_seed)
{
    const SgComplex *cx = c->cx;
    c->slab_planes = slab_planes;
    if (c->slab_planes < SLAB_MIN_PLANES)
        c->slab_planes = SLAB_MIN_PLANES;
    if (c->slab_planes > (size_t)cx->lz)
        c->slab_planes = (size_t)cx->lz;
    c->slab_count = ((size_t)cx->lz + c->slab_planes - 1) / c->slab_planes;
    c->slab_cells = (uint64_t)c->slab_planes * c->st[2] * 8;
    c->threads = parallel_grain && !schedule_seed ? sg_thread_count(threads) : 1;
    c->schedule_state = schedule_seed;
    if (c->threads > MAX_THREADS)
        c->threads = MAX_THREADS;
    if (c->slab_count < 4)
        c->threads = 1; /* too thin to split */
    c->slabs = calloc(c->slab_count, sizeof *c->slabs);
    c->sinks = calloc((size_t)c->threads, sizeof *c->sinks);
    c->done = malloc(c->slab_count);
    c->busy = calloc(c->slab_count, 1);
    c->slab_work = calloc(c->slab_count, sizeof *c->slab_work);
    if (!c->slabs || !c->sinks || !c->done || !c->busy || !c->slab_work)
        return false;
    memset(c->done, KINDS, c->slab_count); /* no step open */
    for (int t = 0; t < c->threads; t++)
        c->sinks[t].noted = t == 0 ? &c->live : &c->sinks[t].own_noted;
    return true;
}

/* Helper threads 1 .. threads-1 (fewer if some cannot start); returns how
 * many started. */
static int start_helpers(Collapse *c, Helper helpers[MAX_THREADS], pthread_t ids[MAX_THREADS])
{
    int started = 0;
    for (int t = 1; t < c->threads; t++) {
        helpers[t] = (Helper){c, t};
        if (pthread_create(&ids[t], NULL, helper_main, &helpers[t]) != 0)
            break;
        started = t;
    }
    c->threads = started + 1;
    return started;
}

static void stop_helpers(Collapse *c, const pthread_t ids[MAX_THREADS], int started)
{
    if (started == 0)
        return;
    pthread_mutex_lock(&c->lock);
    c->exit = true;
    pthread_cond_broadcast(&c->changed);
    pthread_mutex_unlock(&c->lock);
    for (int t = 1; t <= started; t++)
        pthread_join(ids[t], NULL);
}

/* the first free faces: only vertices next to the outside of the medium */
static void queue_first_free_faces(Collapse *c, int threads)
{
    SetupPass setup = {c, calloc(c->slab_count, sizeof *setup.slab)};
    if (!setup.slab) {
        c->oom = true;
        return;
    }
    sg_parallel_for(c->slab_count, threads, setup_slab, &setup);
    for (size_t i = 0; i < c->slab_count; i++) {
        c->total += setup.slab[i].total;
        c->squares += setup.slab[i].squares;
        c->oom |= setup.slab[i].oom;
    }
    free(setup.slab);
}

/* Whether any slab has a cell queued for the next step. */
static bool any_queued(const Collapse *c)
{
    bool any = false;
    for (size_t i = 0; i < c->slab_count && !any; i++)
        for (int source = 0; source < SOURCES; source++)
            for (int k = 0; k < KINDS; k++)
                any |= c->slabs[i].q[source][!c->cur_side][k].n > 0;
    return any;
}

/* Steps until nothing is free and no cavity is left to break. */
static bool collapse_steps(Collapse *c, SgProgress *progress, SgError *err)
{
    if (progress)
        progress->total = c->total; /* cells removed / cells at the start */
    for (;;) {
        if (!any_queued(c)) {
            if (c->squares == 0)
                return true;
            if (!break_cavities(c))
                return false;
            continue;
        }
        c->step++;
        c->cur_side = !c->cur_side;
        run_step(c);
        if (c->stuck)
            sg_fail(err, "collapse: internal error: no (slab, sub-step) ready");
        if (c->oom || c->stuck)
            return false;
        apply_lifespan_rule(c);
        if (c->oom)
            return false;
        if (progress)
            sg_progress_update(progress, c->removed);
    }
}

/* every surviving edge: kept ones, and those still waiting that are present */
static bool collapse_result(Collapse *c, SgCollapseResult *result, SgError *err)
{
    size_t total = c->kept.n + c->live.n + c->far.n;
    for (size_t l = 0; l < c->due_count; l++)
        total += c->due[l].n;
    result->edges = malloc((total ? total : 1) * sizeof *result->edges);
    if (!result->edges) {
        c->oom = true;
        return false;
    }
    size_t w = 0;
    for (size_t i = 0; i < c->kept.n; i++)
        result->edges[w++] = c->kept.a[i];
    gather_present(c, &c->live, result->edges, &w);
    gather_present(c, &c->far, result->edges, &w);
    for (size_t l = 0; l < c->due_count; l++)
        gather_present(c, &c->due[l], result->edges, &w);
    qsort(result->edges, w, sizeof *result->edges, compare_edge_cell);
    result->edge_count = w;
    for (size_t i = 1; i < w; i++)
        if (result->edges[i].cell == result->edges[i - 1].cell) {
            sg_fail(err, "collapse: internal error: edge noted twice");
            c->oom = true;
            return false;
        }
    result->steps = (uint32_t)c->step;
    result->cavities_broken = c->cavities_broken_total;
    result->forced_breaks = c->forced_total;
    return true;
}

static void collapse_release(Collapse *c)
{
    pthread_mutex_destroy(&c->lock);
    pthread_cond_destroy(&c->changed);
    for (size_t i = 0; c->slabs && i < c->slab_count; i++)
        for (int side = 0; side < 2; side++)
            for (int source = 0; source < SOURCES; source++)
                for (int k = 0; k < KINDS; k++)
                    free(c->slabs[i].q[source][side][k].a);
    free(c->slabs);
    for (int side = 0; side < 2; side++)
        for (int k = 0; k < KINDS; k++)
            free(c->staged.q[SOURCE_OWN][side][k].a);
    for (int t = 0; c->sinks && t < c->threads; t++) {
        free(c->sinks[t].pairs.a);
        free(c->sinks[t].own_noted.a);
    }
    free(c->sinks);
    free(c->done);
    free(c->busy);
    free(c->slab_work);
    free(c->live.a);
    for (size_t l = 0; l < c->due_count; l++)
        free(c->due[l].a);
    free(c->due);
    free(c->far.a);
    free(c->kept.a);
    free(c->cons.slot);
}

bool sg_collapse(SgComplex *cx, const uint32_t *constrained, size_t constrained_count,
                 const uint16_t *dist8, const uint16_t *open8, double filter_scale,
                 int threads, uint32_t parallel_grain, uint32_t slab_planes,
                 uint64_t schedule_seed, SgProgress *progress, SgCollapseResult *result,
                 SgError *err)
{
    memset(result, 0, sizeof *result);
    Helper helpers[MAX_THREADS];
    pthread_t ids[MAX_THREADS];
    int started = 0;
    Collapse c = {.cx = cx, .cells = cx->cells, .dist8 = dist8, .open8 = open8};
    pthread_mutex_init(&c.lock, NULL);
    pthread_cond_init(&c.changed, NULL);
    /* the rule compares 8 x lifespan with scale x (8 x opening): in 1/256 */
    c.filter256 = filter_scale >= 0 && filter_scale < 1e6 ? (int64_t)(filter_scale * 256 + 0.5) : 256;
    for (int a = 0; a < 3; a++)
        c.st[a] = cx->stride[a];
    bool ok = collapse_set_constraints(&c, constrained, constrained_count) &&
              collapse_plan_slabs(&c, threads, parallel_grain, slab_planes, schedule_seed);
    if (ok) {
        started = start_helpers(&c, helpers, ids);
        queue_first_free_faces(&c, threads);
        ok = !c.oom && collapse_steps(&c, progress, err) && collapse_result(&c, result, err);
    }
    stop_helpers(&c, ids, started);
    collapse_release(&c);
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
