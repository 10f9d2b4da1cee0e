/* Distance transform and opening values of the medium.
 *
 * Distance: exact squared Euclidean distance transform, separable
 * (Felzenszwalb & Huttenlocher's lower envelope of parabolas, one axis at a
 * time); lines are independent, so they run on worker threads with results
 * that do not depend on the thread count.
 *
 * Opening: open(p) = max { R(q) : |p - q| < R(q) } where R(q) is the
 * distance at q (the largest ball centred at q inside the medium). Painting
 * every ball costs the sum of ball volumes, far too much at 30 M voxels, so
 * each voxel carries its best ball centre and hands it on to its neighbour
 * along x, then y, then z (both orientations). The staircase path x, then
 * y, then z from q to any p in the ball stays in the ball, so every p can
 * be reached; a relay that already holds a larger ball not containing p
 * blocks it, which makes the value a slight underestimate in places (the
 * tests measure it against brute force). */
#include "skeletonize.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "threads.h"
#include "memory.h"

typedef struct EdtContext {
    const SgGrid *grid;
    uint32_t *d2;
    uint16_t *d2_16; /* d2 shrunk to 16 bits for the opening, when it fits */
    int threads;
    /* per-thread scratch: f, out (uint32), v (int), z (double) of the longest axis */
    uint32_t **f_buf, **out_buf;
    int **v_buf;
    double **z_buf;
    uint32_t *plane_max; /* per z plane: the largest value after the y pass */
    uint16_t *z_out16;   /* the z pass's output in 16 bits, when every value fits */
    /* opening */
    uint32_t *cand;
    int bx, by; /* bit widths of packed x, y */
    /* output */
    const uint16_t *eighths; /* to_eighths of every 16-bit squared distance */
    bool lattice;        /* output in the collapse's lattice layout (see layout_row) */
} EdtContext;

/* Lower envelope of parabolas f[q] + (i - q)^2 over q in [0, n), plus the
 * outside of the grid as zero-cost sites at -1 and n. */
static void envelope_1d(const uint32_t *f, uint32_t *out, int n, int *v, double *z)
{
    int k = 0;
    v[0] = 0;
    z[0] = -1e30;
    z[1] = 1e30;
    for (int q = 1; q < n; q++) {
        double fq = (double)f[q] + (double)q * q;
        double s;
        for (;;) {
            int p = v[k];
            s = (fq - ((double)f[p] + (double)p * p)) / (2.0 * (q - p));
            if (s <= z[k] && k > 0)
                k--;
            else
                break;
        }
        if (s <= z[k]) { /* k == 0 and q dominates everything */
            v[0] = q;
            z[0] = -1e30;
            z[1] = 1e30;
            continue;
        }
        k++;
        v[k] = q;
        z[k] = s;
        z[k + 1] = 1e30;
    }
    k = 0;
    for (int i = 0; i < n; i++) {
        while (z[k + 1] < i)
            k++;
        uint64_t d = (uint64_t)f[v[k]] + (uint64_t)((int64_t)(i - v[k]) * (i - v[k]));
        uint64_t lo = (uint64_t)(i + 1) * (uint64_t)(i + 1);
        uint64_t hi = (uint64_t)(n - i) * (uint64_t)(n - i);
        if (lo < d) d = lo;
        if (hi < d) d = hi;
        out[i] = d > UINT32_MAX ? UINT32_MAX : (uint32_t)d;
    }
}

/* x: one pass each way gives the distance to the nearest outside voxel on the row. */
static void edt_x(void *vctx, uint64_t index, int thread)
{
    (void)thread;
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t row = (size_t)index * (size_t)g->nx;
    const uint8_t *in = g->voxels + row;
    uint32_t *d2 = c->d2 + row;
    int last = -1;
    for (int i = 0; i < g->nx; i++) {
        if (!in[i]) last = i;
        d2[i] = (uint32_t)(i - last); /* distance, squared below */
    }
    last = g->nx;
    for (int i = g->nx - 1; i >= 0; i--) {
        if (!in[i]) last = i;
        uint32_t d = d2[i], e = (uint32_t)(last - i);
        if (e < d) d = e;
        d2[i] = in[i] ? d * d : 0;
    }
}

/* The 1D pass along one line of d2: n values from `line`, `stride` apart,
 * through the thread's buffers, written back (a line with no medium is
 * left as it is) or, with line16, to the same places of the 16-bit array
 * (the caller knows they fit). */
static inline void edt_line(const EdtContext *c, int thread, uint32_t *line, uint16_t *line16,
                            size_t stride, int n)
{
    uint32_t *f = c->f_buf[thread], *out = c->out_buf[thread];
    bool any = false;
    for (int i = 0; i < n; i++) {
        f[i] = line[stride * (size_t)i];
        any |= f[i] != 0;
    }
    if (any)
        envelope_1d(f, out, n, c->v_buf[thread], c->z_buf[thread]);
    if (line16) {
        for (int i = 0; i < n; i++)
            line16[stride * (size_t)i] = (uint16_t)(f[i] ? out[i] : 0);
        return;
    }
    if (!any)
        return;
    for (int i = 0; i < n; i++)
        if (f[i]) line[stride * (size_t)i] = out[i];
}

/* y: one z slice per task (the slice stays in cache). */
static void edt_y(void *vctx, uint64_t z, int thread)
{
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t nx = (size_t)g->nx;
    size_t count = nx * (size_t)g->ny;
    uint32_t *slice = c->d2 + (size_t)z * count, largest = 0;
    for (size_t x = 0; x < nx; x++)
        edt_line(c, thread, slice + x, NULL, nx, g->ny);
    for (size_t i = 0; i < count; i++)
        largest = slice[i] > largest ? slice[i] : largest;
    c->plane_max[z] = largest;
}

/* z: one y row per task. */
static void edt_z(void *vctx, uint64_t y, int thread)
{
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t nx = (size_t)g->nx, plane = nx * (size_t)g->ny;
    uint32_t *base = c->d2 + (size_t)y * nx;
    uint16_t *base16 = c->z_out16 ? c->z_out16 + (size_t)y * nx : NULL;
    for (size_t x = 0; x < nx; x++)
        edt_line(c, thread, base + x, base16 ? base16 + x : NULL, plane, g->nz);
}

/* ---- opening ----------------------------------------------------------- */

static inline uint32_t pack(const EdtContext *c, int x, int y, int z)
{
    return (uint32_t)x | (uint32_t)y << c->bx | (uint32_t)z << (c->bx + c->by);
}

static inline uint32_t squared_distance(const EdtContext *c, size_t v)
{
    return c->d2_16 ? c->d2_16[v] : c->d2[v];
}

/* Offer ball centre cq (packed) to voxel p at (x,y,z): taken when larger
 * than p's current ball and containing p. */
static inline void offer(const EdtContext *c, size_t p, int x, int y, int z, uint32_t cq)
{
    const SgGrid *g = c->grid;
    uint32_t cp = c->cand[p];
    if (cp == cq)
        return;
    int qx = (int)(cq & ((1u << c->bx) - 1));
    int qy = (int)(cq >> c->bx & ((1u << c->by) - 1));
    int qz = (int)(cq >> (c->bx + c->by));
    int px = (int)(cp & ((1u << c->bx) - 1));
    int py = (int)(cp >> c->bx & ((1u << c->by) - 1));
    int pz = (int)(cp >> (c->bx + c->by));
    uint32_t rq = squared_distance(c, (size_t)qx + (size_t)g->nx * ((size_t)qy + (size_t)g->ny * (size_t)qz));
    uint32_t rp = squared_distance(c, (size_t)px + (size_t)g->nx * ((size_t)py + (size_t)g->ny * (size_t)pz));
    if (rq <= rp)
        return;
    int64_t dx = x - qx, dy = y - qy, dz = z - qz;
    if ((uint64_t)(dx * dx + dy * dy + dz * dz) < rq)
        c->cand[p] = cq;
}

static void open_x(void *vctx, uint64_t z, int thread)
{
    (void)thread;
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t nx = (size_t)g->nx;
    for (int y = 0; y < g->ny; y++) {
        size_t row = nx * ((size_t)y + (size_t)g->ny * z);
        for (int x = 1; x < g->nx; x++)
            if (c->grid->voxels[row + x] && c->grid->voxels[row + x - 1])
                offer(c, row + x, x, y, (int)z, c->cand[row + x - 1]);
        for (int x = g->nx - 2; x >= 0; x--)
            if (c->grid->voxels[row + x] && c->grid->voxels[row + x + 1])
                offer(c, row + x, x, y, (int)z, c->cand[row + x + 1]);
    }
}

static void open_y(void *vctx, uint64_t z, int thread)
{
    (void)thread;
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t nx = (size_t)g->nx;
    size_t slice = nx * (size_t)g->ny * z;
    /* whole rows at a time: x innermost for locality */
    for (int y = 1; y < g->ny; y++)
        for (int x = 0; x < g->nx; x++) {
            size_t p = slice + x + nx * (size_t)y;
            if (c->grid->voxels[p] && c->grid->voxels[p - nx])
                offer(c, p, x, y, (int)z, c->cand[p - nx]);
        }
    for (int y = g->ny - 2; y >= 0; y--)
        for (int x = 0; x < g->nx; x++) {
            size_t p = slice + x + nx * (size_t)y;
            if (c->grid->voxels[p] && c->grid->voxels[p + nx])
                offer(c, p, x, y, (int)z, c->cand[p + nx]);
        }
}

static void open_z(void *vctx, uint64_t y, int thread)
{
    (void)thread;
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t nx = (size_t)g->nx, plane = nx * (size_t)g->ny;
    size_t row = nx * y;
    for (int z = 1; z < g->nz; z++)
        for (int x = 0; x < g->nx; x++) {
            size_t p = row + x + plane * (size_t)z;
            if (c->grid->voxels[p] && c->grid->voxels[p - plane])
                offer(c, p, x, (int)y, z, c->cand[p - plane]);
        }
    for (int z = g->nz - 2; z >= 0; z--)
        for (int x = 0; x < g->nx; x++) {
            size_t p = row + x + plane * (size_t)z;
            if (c->grid->voxels[p] && c->grid->voxels[p + plane])
                offer(c, p, x, (int)y, z, c->cand[p + plane]);
        }
}

static int bit_width(int n)
{
    int b = 1;
    while ((1 << b) < n)
        b++;
    return b;
}

static inline uint16_t to_eighths(uint32_t d2)
{
    double v = 8.0 * sqrt((double)d2) + 0.5;
    return v >= 65535.0 ? 65535 : (uint16_t)v;
}

static inline uint16_t eighths_of(const EdtContext *c, uint32_t d2)
{
    return d2 < 65536 ? c->eighths[d2] : to_eighths(d2);
}

/* Each voxel of plane z starts as its own ball centre. */
static void cand_init(void *vctx, uint64_t z, int thread)
{
    (void)thread;
    EdtContext *c = vctx;
    const SgGrid *g = c->grid;
    size_t p = (size_t)z * (size_t)g->nx * (size_t)g->ny;
    for (int y = 0; y < g->ny; y++)
        for (int x = 0; x < g->nx; x++, p++)
            c->cand[p] = pack(c, x, y, (int)z);
}

/* ---- output: 16-bit values in the grid's layout or the lattice's ------ */

/* Where voxel (0, y, z)'s value goes: the grid's layout, or the collapse's
 * lattice (sizes n + 3, voxel (x, y, z) at vertex (x + 1, y + 1, z + 1):
 * complex.h), whose padding is zero. */
static size_t layout_row(const EdtContext *c, int y, int z)
{
    const SgGrid *g = c->grid;
    if (!c->lattice)
        return (size_t)g->nx * ((size_t)y + (size_t)g->ny * (size_t)z);
    size_t lx = (size_t)g->nx + 3, ly = (size_t)g->ny + 3;
    return 1 + lx * ((size_t)y + 1 + ly * ((size_t)z + 1));
}

static size_t layout_count(const EdtContext *c)
{
    const SgGrid *g = c->grid;
    if (!c->lattice)
        return sg_grid_count(g);
    return ((size_t)g->nx + 3) * ((size_t)g->ny + 3) * ((size_t)g->nz + 3);
}

/* A plane's values (nx * ny, x fastest) from the source array src. */
typedef void (*PlaneValues)(const EdtContext *c, const void *src, int z, uint16_t *out);

/* open8 of plane z from the ball centres (src) and the squared distances. */
static void opening_plane(const EdtContext *c, const void *src, int z, uint16_t *out)
{
    const SgGrid *g = c->grid;
    const size_t count = (size_t)g->nx * (size_t)g->ny, base = count * (size_t)z;
    const uint32_t *cand = (const uint32_t *)src + base;
    const uint32_t mx = (1u << c->bx) - 1, my = (1u << c->by) - 1;
    for (size_t i = 0; i < count; i++) {
        uint32_t cq = cand[i];
        size_t q = (cq & mx) + (size_t)g->nx * ((cq >> c->bx & my) +
                                                (size_t)g->ny * (cq >> (c->bx + c->by)));
        out[i] = g->voxels[base + i] ? eighths_of(c, squared_distance(c, q)) : 0;
    }
}

/* dist8 of plane z from the squared distances (src: 16 bits when d2_16 is set). */
static void distance_plane(const EdtContext *c, const void *src, int z, uint16_t *out)
{
    const SgGrid *g = c->grid;
    const size_t count = (size_t)g->nx * (size_t)g->ny, base = count * (size_t)z;
    if (c->d2_16) {
        const uint16_t *d2 = (const uint16_t *)src + base;
        for (size_t i = 0; i < count; i++)
            out[i] = c->eighths[d2[i]];
    } else {
        const uint32_t *d2 = (const uint32_t *)src + base;
        for (size_t i = 0; i < count; i++)
            out[i] = eighths_of(c, d2[i]);
    }
}

typedef struct PlaneBatch {
    const EdtContext *c;
    PlaneValues values;
    const void *src;
    int first, dir;     /* plane of batch entry i: first + dir * i */
    uint16_t *scratch;  /* a plane per entry */
} PlaneBatch;

static void batch_plane(void *ctx, uint64_t i, int thread)
{
    (void)thread;
    PlaneBatch *b = ctx;
    const SgGrid *g = b->c->grid;
    b->values(b->c, b->src, b->first + b->dir * (int)i,
              b->scratch + i * (size_t)g->nx * (size_t)g->ny);
}

/* Rewrites buffer (capacity bytes), a value of src_size bytes per voxel in
 * the grid's layout, as the 16-bit values `values` computes, in the output
 * layout, in the same memory (grown if need be: allocate it large enough,
 * a realloc that moves it costs a fresh array's first touch): planes are computed a batch at a time on the
 * threads into scratch, then copied to their place. The order keeps every
 * batch's writes off the planes still to read: with 4-byte sources the
 * output lies below them (planes upwards), with 2-byte ones at or above
 * them (downwards). Where that does not hold (a tiny grid, whose padding
 * weighs more than the halved values save) the output gets its own
 * array. On success the buffer is consumed and the output returned; NULL:
 * out of memory, the buffer untouched. */
static uint16_t *to_layout(EdtContext *c, void *buffer, size_t capacity, size_t src_size,
                           PlaneValues values)
{
    const SgGrid *g = c->grid;
    const size_t nx = (size_t)g->nx, plane = nx * (size_t)g->ny;
    const size_t in_bytes = capacity, out_bytes = layout_count(c) * 2;
    const int batch = c->threads > 2 ? c->threads : 2, dir = src_size == 4 ? 1 : -1;
    bool in_place = src_size != 4 || out_bytes <= in_bytes;
    for (int n = 0; n < g->nz && in_place; n += batch) {
        int k = g->nz - n < batch ? g->nz - n : batch;
        if (dir > 0) { /* writes up to the batch's last plane's end, reads from the next plane */
            int last = n + k - 1;
            in_place = 2 * (layout_row(c, g->ny - 1, last) + nx) <= src_size * plane * (size_t)(last + 1);
        } else { /* writes down to the batch's lowest plane's start, read up to it */
            int low = g->nz - n - k;
            in_place = 2 * layout_row(c, 0, low) >= src_size * plane * (size_t)low;
        }
    }
    uint16_t *scratch = malloc((size_t)batch * plane * sizeof *scratch);
    SgThreadPool *pool = sg_thread_pool_create(c->threads);
    uint16_t *out = NULL;
    if (scratch && pool) {
        if (!in_place)
            out = malloc(out_bytes);
        else if (out_bytes > in_bytes)
            out = realloc(buffer, out_bytes);
        else
            out = buffer;
    }
    if (!out) {
        free(scratch);
        sg_thread_pool_free(pool);
        return NULL;
    }
    if (in_place)
        buffer = out;
    for (int n = 0; n < g->nz; n += batch) {
        int k = g->nz - n < batch ? g->nz - n : batch;
        PlaneBatch b = {c, values, buffer, dir > 0 ? n : g->nz - 1 - n, dir, scratch};
        sg_thread_pool_run(pool, (uint64_t)k, batch_plane, &b);
        for (int i = 0; i < k; i++)
            for (int y = 0; y < g->ny; y++)
                memcpy(out + layout_row(c, y, b.first + dir * i), scratch + (size_t)i * plane + nx * (size_t)y,
                       nx * sizeof *out);
    }
    free(scratch);
    sg_thread_pool_free(pool);
    if (c->lattice) { /* zero the padding */
        const size_t lx = nx + 3, lplane = lx * ((size_t)g->ny + 3);
        memset(out, 0, (lplane + lx + 1) * sizeof *out);
        for (int z = 0; z < g->nz; z++) {
            uint16_t *p = out + lplane * (size_t)(z + 1);
            if (z > 0)
                memset(p, 0, (lx + 1) * sizeof *out);
            for (int y = 0; y < g->ny; y++) { /* the row's end and the next row's start */
                size_t r = 1 + lx * (size_t)(y + 1);
                memset(p + r + nx, 0, (lx - nx) * sizeof *out);
            }
            size_t tail = 1 + lx * (size_t)(g->ny + 1);
            memset(p + tail, 0, (lplane - tail) * sizeof *out);
        }
        memset(out + lplane * (size_t)(g->nz + 1), 0, 2 * lplane * sizeof *out);
    }
    if (!in_place) {
        free(buffer);
    } else if (out_bytes < in_bytes) {
        void *shrunk = realloc(out, out_bytes);
        out = shrunk ? shrunk : out;
    }
    sg_memory_prefer_huge_pages(out, out_bytes); /* the collapse reads them at random */
    return out;
}

/* dist8 and open8 in the grid's layout (lattice false) or the lattice's. */
/* The squared distances, the per-thread line buffers (longest voxels
 * each) and the table of distances in eighths of a voxel. */
static bool edt_alloc(EdtContext *c, size_t n, int longest, uint16_t **eighths)
{
    const SgGrid *g = c->grid;
    c->d2 = malloc(n * sizeof *c->d2);
    c->plane_max = calloc((size_t)g->nz, sizeof *c->plane_max);
    c->f_buf = calloc((size_t)c->threads, sizeof *c->f_buf);
    c->out_buf = calloc((size_t)c->threads, sizeof *c->out_buf);
    c->v_buf = calloc((size_t)c->threads, sizeof *c->v_buf);
    c->z_buf = calloc((size_t)c->threads, sizeof *c->z_buf);
    *eighths = malloc(65536 * sizeof **eighths);
    if (!c->d2 || !c->plane_max || !c->f_buf || !c->out_buf || !c->v_buf || !c->z_buf || !*eighths)
        return false;
    for (uint32_t d = 0; d < 65536; d++)
        (*eighths)[d] = to_eighths(d);
    c->eighths = *eighths;
    sg_memory_prefer_huge_pages(c->d2, n * sizeof *c->d2);
    for (int t = 0; t < c->threads; t++) {
        c->f_buf[t] = malloc((size_t)longest * sizeof(uint32_t));
        c->out_buf[t] = malloc((size_t)longest * sizeof(uint32_t));
        c->v_buf[t] = malloc((size_t)longest * sizeof(int));
        c->z_buf[t] = malloc(((size_t)longest + 1) * sizeof(double));
        if (!c->f_buf[t] || !c->out_buf[t] || !c->v_buf[t] || !c->z_buf[t])
            return false;
    }
    return true;
}

/* The z pass of the distance transform. The opening needs the exact
 * squared distances at ball centres; the medium test reads the grid (d2 >
 * 0 exactly on the medium). The z pass only lowers values: when every
 * value after the y pass fits 16 bits (distances under 256 voxels), the z
 * pass writes 16-bit values to an array of their own and the 32-bit one
 * goes. The opening's peak is then 7 bytes a voxel (grid, d2, ball
 * centres) instead of 9. *d2_16_bytes: the size of the 16-bit array. */
static bool edt_z_pass(EdtContext *c, size_t n, size_t *d2_16_bytes)
{
    const SgGrid *g = c->grid;
    uint32_t bound = 0;
    for (int z = 0; z < g->nz; z++)
        bound = c->plane_max[z] > bound ? c->plane_max[z] : bound;
    *d2_16_bytes = n * sizeof *c->d2_16;
    if (bound < 65536) {
        /* room for dist8 in the output layout, written over it at the end */
        if (layout_count(c) > n)
            *d2_16_bytes = layout_count(c) * sizeof *c->d2_16;
        c->z_out16 = malloc(*d2_16_bytes);
        if (!c->z_out16)
            return false;
        sg_memory_prefer_huge_pages(c->z_out16, *d2_16_bytes);
        sg_parallel_for((uint64_t)g->ny, c->threads, edt_z, c);
        /* the 32-bit array, done with, holds the ball centres next: its
         * pages are the process's already (the kernel clears every page
         * a fresh array touches: a fifth of this step's time at 1000) */
        c->cand = (uint32_t *)c->d2;
        c->d2 = NULL;
        c->d2_16 = c->z_out16;
        c->z_out16 = NULL;
        return true;
    }
    sg_parallel_for((uint64_t)g->ny, c->threads, edt_z, c);
    uint32_t largest = 0;
    for (size_t i = 0; i < n; i++)
        largest = c->d2[i] > largest ? c->d2[i] : largest;
    if (largest < 65536) { /* shrunk in place */
        uint16_t *d16 = (uint16_t *)(void *)c->d2;
        for (size_t i = 0; i < n; i++) {
            uint16_t v = (uint16_t)c->d2[i];
            memcpy(d16 + i, &v, sizeof v);
        }
        void *shrunk = realloc(c->d2, n * sizeof(uint16_t));
        c->d2_16 = shrunk ? shrunk : (void *)c->d2;
        c->d2 = NULL;
    }
    return true;
}

/* The opening (radius of the largest ball inside the medium that covers
 * each voxel), in eighths, in the output layout. */
static bool opening(EdtContext *c, size_t n, uint16_t **open8_out)
{
    const SgGrid *g = c->grid;
    if (!c->cand) {
        c->cand = malloc(n * sizeof *c->cand);
        if (!c->cand)
            return false;
        sg_memory_prefer_huge_pages(c->cand, n * sizeof *c->cand);
    }
    sg_parallel_for((uint64_t)g->nz, c->threads, cand_init, c);
    /* one round x, y, z; a second round would lower the mean
     * underestimate from ~0.56 to ~0.33 voxel (noisy walls) at twice
     * the cost: not worth it for a threshold counted in whole steps */
    sg_parallel_for((uint64_t)g->nz, c->threads, open_x, c);
    sg_parallel_for((uint64_t)g->nz, c->threads, open_y, c);
    sg_parallel_for((uint64_t)g->ny, c->threads, open_z, c);
    *open8_out = to_layout(c, c->cand, n * sizeof *c->cand, sizeof *c->cand, opening_plane);
    if (!*open8_out)
        return false;
    c->cand = NULL;
    return true;
}

/* The distance in eighths, in the output layout. */
static bool distance_eighths(EdtContext *c, size_t n, size_t d2_16_bytes, uint16_t **dist8_out)
{
    if (c->d2_16) {
        *dist8_out = to_layout(c, c->d2_16, d2_16_bytes, sizeof *c->d2_16, distance_plane);
        if (*dist8_out)
            c->d2_16 = NULL;
    } else {
        *dist8_out = to_layout(c, c->d2, n * sizeof *c->d2, sizeof *c->d2, distance_plane);
        if (*dist8_out)
            c->d2 = NULL;
    }
    return *dist8_out != NULL;
}

static void edt_release(EdtContext *c)
{
    for (int t = 0; t < c->threads && c->f_buf; t++) {
        free(c->f_buf[t]);
        free(c->out_buf ? c->out_buf[t] : NULL);
        free(c->v_buf ? c->v_buf[t] : NULL);
        free(c->z_buf ? c->z_buf[t] : NULL);
    }
    free(c->f_buf);
    free(c->out_buf);
    free(c->v_buf);
    free(c->z_buf);
    free(c->plane_max);
    free(c->d2);
    free(c->d2_16);
    free(c->z_out16);
    free(c->cand);
}

static bool distance_opening(const SgGrid *g, int threads, bool lattice, uint16_t **dist8_out,
                             uint16_t **open8_out, SgError *err)
{
    *dist8_out = NULL;
    if (open8_out)
        *open8_out = NULL;
    size_t n = sg_grid_count(g);
    if (n == 0)
        return sg_fail(err, "distance transform: empty grid");
    EdtContext c = {.grid = g, .threads = sg_thread_count(threads), .lattice = lattice};
    c.bx = bit_width(g->nx);
    c.by = bit_width(g->ny);
    int bz = bit_width(g->nz);
    if (c.bx + c.by + bz > 32)
        return sg_fail(err, "distance transform: grid %dx%dx%d too large", g->nx, g->ny, g->nz);
    int longest = g->nx > g->ny ? g->nx : g->ny;
    if (g->nz > longest) longest = g->nz;

    uint16_t *eighths = NULL;
    size_t d2_16_bytes = 0;
    bool ok = edt_alloc(&c, n, longest, &eighths);
    if (ok) {
        sg_parallel_for((uint64_t)g->ny * (uint64_t)g->nz, c.threads, edt_x, &c);
        sg_parallel_for((uint64_t)g->nz, c.threads, edt_y, &c);
        ok = edt_z_pass(&c, n, &d2_16_bytes) && (!open8_out || opening(&c, n, open8_out)) &&
             distance_eighths(&c, n, d2_16_bytes, dist8_out);
    }
    edt_release(&c);
    free(eighths);
    if (!ok) {
        if (open8_out) {
            free(*open8_out);
            *open8_out = NULL;
        }
        return sg_fail(err, "distance transform: out of memory for %dx%dx%d voxels", g->nx,
                       g->ny, g->nz);
    }
    return true;
}

bool sg_distance_opening(const SgGrid *g, int threads, uint16_t **dist8, uint16_t **open8,
                         SgError *err)
{
    return distance_opening(g, threads, false, dist8, open8, err);
}

bool sg_distance_opening_lattice(const SgGrid *g, int threads, uint16_t **dist8,
                                 uint16_t **open8, SgError *err)
{
    return distance_opening(g, threads, true, dist8, open8, err);
}
