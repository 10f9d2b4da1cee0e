/* sg_importance_build: labels, shortest paths, importance points, then the
 * cache file laid out as in docs/cache-format.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "graph.h"
#include "hash.h"
#include "importance.h"
#include "importance_cache_format.h"
#include "labels.h"
#include "memory.h"
#include "output_file.h"
#include "ply_file.h"
#include "progress.h"
#include "threads.h"

static size_t align_up(size_t v) { return (v + SG_CACHE_ALIGN - 1) & ~(size_t)(SG_CACHE_ALIGN - 1); }

/* ---- nearest-node table: 8x8x8 blocks with a per-block node palette ---- */

typedef struct BlockPass {
    const SgLabelGrid *labels;
    int bx, by, bz;
    /* pass 1 output, per block */
    uint16_t *palette_size;
    uint8_t *bits;
    /* pass 2 input/output */
    const uint32_t *block_index;  /* per grid block: record or NONE */
    SgCacheBlock *records;
    uint32_t *palette;
    uint8_t *voxel_bits;
} BlockPass;

/* Labels of one block in local order (x fastest); NONE outside the grid. */
static void block_labels(const SgLabelGrid *l, int bi, int bj, int bk, uint32_t out[512])
{
    if (l->key32 && (bi + 1) * 8 <= l->nx && (bj + 1) * 8 <= l->ny && (bk + 1) * 8 <= l->nz) {
        /* inside the grid, 32-bit keys (the common case): rows of keys */
        const uint32_t mask = l->node_mask;
        for (int z = 0; z < 8; z++)
            for (int y = 0; y < 8; y++) {
                const uint32_t *row = l->key32 + (size_t)(bi * 8 + 1) +
                                      l->px * ((size_t)(bj * 8 + y + 1) + l->py * (size_t)(bk * 8 + z + 1));
                for (int x = 0; x < 8; x++) {
                    uint32_t node = row[x] & mask;
                    *out++ = node == mask ? SG_CACHE_NONE : node;
                }
            }
        return;
    }
    int n = 0;
    for (int z = 0; z < 8; z++)
        for (int y = 0; y < 8; y++)
            for (int x = 0; x < 8; x++, n++) {
                int i = bi * 8 + x, j = bj * 8 + y, k = bk * 8 + z;
                out[n] = (i < l->nx && j < l->ny && k < l->nz) ? sg_label_at(l, i, j, k)
                                                               : SG_CACHE_NONE;
            }
}

/* Distinct labels in order of first appearance; index[v] into it. */
static int block_palette(const uint32_t labels[512], uint32_t palette[512], uint16_t index[512])
{
    int size = 0, last = 0;
    for (int v = 0; v < 512; v++) {
        uint32_t l = labels[v];
        if (size == 0 || palette[last] != l) {
            int p = 0;
            while (p < size && palette[p] != l)
                p++;
            if (p == size)
                palette[size++] = l;
            last = p;
        }
        index[v] = (uint16_t)last;
    }
    return size;
}

static uint8_t bits_for(int palette_size)
{
    if (palette_size <= 1) return 0;
    if (palette_size <= 2) return 1;
    if (palette_size <= 4) return 2;
    if (palette_size <= 16) return 4;
    if (palette_size <= 256) return 8;
    return 16;
}

/* Block (bi, bj, bk)'s palette and each voxel's index into it; its size. */
static int block_palette_at(const BlockPass *p, int bi, int bj, int bk, uint32_t palette[512], uint16_t index[512])
{
    uint32_t labels[512];
    block_labels(p->labels, bi, bj, bk, labels);
    return block_palette(labels, palette, index);
}

/* visit(p, b, bi, bj, bk) for every block b of the slab bk. */
static void each_block_of_slab(BlockPass *p, int bk, void (*visit)(BlockPass *, size_t, int, int, int))
{
    for (int bj = 0; bj < p->by; bj++)
        for (int bi = 0; bi < p->bx; bi++)
            visit(p, (size_t)bi + (size_t)p->bx * ((size_t)bj + (size_t)p->by * (size_t)bk), bi, bj, bk);
}

/* Pass 1: a block's palette size and bits per voxel. */
static void count_block(BlockPass *p, size_t b, int bi, int bj, int bk)
{
    uint32_t palette[512];
    uint16_t index[512];
    int size = block_palette_at(p, bi, bj, bk, palette, index);
    if (size == 1 && palette[0] == SG_CACHE_NONE)
        size = 0; /* nothing labelled: no block stored */
    p->palette_size[b] = (uint16_t)size;
    p->bits[b] = bits_for(size);
}

/* Pass 2: a stored block's palette and packed indices. */
static void encode_block(BlockPass *p, size_t b, int bi, int bj, int bk)
{
    if (p->block_index[b] == SG_CACHE_NONE)
        return;
    const SgCacheBlock *r = &p->records[p->block_index[b]];
    uint32_t palette[512];
    uint16_t index[512];
    block_palette_at(p, bi, bj, bk, palette, index);
    memcpy(p->palette + r->palette_offset, palette, r->palette_size * sizeof *palette);
    uint8_t *data = p->voxel_bits + r->data_offset;
    if (r->bits == 16) {
        for (int v = 0; v < 512; v++) {
            data[2 * v] = (uint8_t)index[v];
            data[2 * v + 1] = (uint8_t)(index[v] >> 8);
        }
    } else if (r->bits > 0) {
        memset(data, 0, (size_t)64 * r->bits);
        for (int v = 0; v < 512; v++) {
            unsigned bit = (unsigned)v * r->bits;
            data[bit >> 3] |= (uint8_t)(index[v] << (bit & 7));
        }
    }
}

static void block_count_slab(void *ctx, uint64_t bk, int thread)
{
    (void)thread;
    each_block_of_slab(ctx, (int)bk, count_block);
}

static void block_encode_slab(void *ctx, uint64_t bk, int thread)
{
    (void)thread;
    each_block_of_slab(ctx, (int)bk, encode_block);
}

/* ---- importance points, in parallel over chunks of nodes --------------- */

typedef struct PointPass {
    const SgVisibility *vis;
    const SgSkeleton *skeleton;
    const uint32_t *component;
    uint32_t light_component;
    const uint32_t *pred;
    const double *dist;
    const double *light_position;
    float *points; /* node_count * light_count * 3 */
    uint32_t light, light_count;
    double tolerance;
    const double *toward_sun; /* a sun's: its nodes look toward it; NULL: another light */
    double reach;             /* how far toward it (the grid's diagonal) */
} PointPass;

enum { POINT_CHUNK = 32 };

static void point_chunk(void *ctx, uint64_t chunk, int thread)
{
    (void)thread;
    PointPass *p = ctx;
    uint64_t end = (chunk + 1) * POINT_CHUNK;
    if (end > p->skeleton->node_count)
        end = p->skeleton->node_count;
    for (uint64_t n = chunk * POINT_CHUNK; n < end; n++) {
        float *out = p->points + ((size_t)n * p->light_count + p->light) * 3;
        if (p->component[n] != p->light_component || !isfinite(p->dist[n])) {
            out[0] = out[1] = out[2] = 0;
            continue;
        }
        if (p->toward_sun && p->dist[n] == 0) { /* in the sun's rays: toward the sun itself */
            for (int a = 0; a < 3; a++)
                out[a] = (float)(p->skeleton->nodes[n].position[a] + p->reach * p->toward_sun[a]);
            continue;
        }
        sg_importance_point(p->vis, p->skeleton, p->pred, p->dist, (uint32_t)n,
                            p->light_position, p->tolerance, out);
    }
}

/* Whether a sun's rays reach voxel v through the medium: a walk from its
 * centre toward the sun, half a voxel a step, that leaves the grid before
 * it meets a voxel that is not medium. */
static bool sunlit(const SgGrid *g, const int v[3], const double toward_sun[3])
{
    double x[3] = {v[0] + 0.5, v[1] + 0.5, v[2] + 0.5};
    for (;;) {
        for (int a = 0; a < 3; a++)
            x[a] += 0.5 * toward_sun[a];
        int i = (int)floor(x[0]), j = (int)floor(x[1]), k = (int)floor(x[2]);
        if (!sg_grid_inside(g, i, j, k))
            return true;
        if (!g->voxels[sg_grid_index(g, i, j, k)])
            return false;
    }
}

/* Whether a voxel lies in the air added round a scene lit from outside:
 * there the sky is, every node there is the outside light. */
static bool in_margin(const SgGrid *g, int margin, const int v[3])
{
    if (margin <= 0)
        return false;
    int dims[3] = {g->nx, g->ny, g->nz};
    for (int a = 0; a < 3; a++)
        if (v[a] < margin || v[a] >= dims[a] - margin)
            return true;
    return false;
}

/* ---- vectors.ply: node -> importance point, one edge per node and light - */

static bool write_vectors(const char *path, const SgSkeleton *s, const uint32_t *component,
                          const SgCacheLight *lights, uint32_t light_count, const float *points,
                          SgError *err)
{
    uint64_t edges = 0;
    for (uint32_t n = 0; n < s->node_count; n++)
        for (uint32_t k = 0; k < light_count; k++)
            edges += lights[k].component != SG_CACHE_NONE && component[n] == lights[k].component;
    if (edges * 2 > INT32_MAX)
        return sg_fail(err, "%s: too many vectors for a PLY file", path);
    SgOutputFile out;
    if (!sg_ply_write_begin(&out, path,
                            "importance points (Biri & Chaussard 2012, figure 2): one edge per node and "
                            "light, from the node to its importance point",
                            err))
        return false;
    fprintf(out.file,
            "element vertex %llu\nproperty float x\nproperty float y\nproperty float z\n"
            "element edge %llu\nproperty int vertex1\nproperty int vertex2\nproperty int light\n"
            "end_header\n",
            (unsigned long long)(2 * edges), (unsigned long long)edges);
    for (uint32_t n = 0; n < s->node_count; n++)
        for (uint32_t k = 0; k < light_count; k++)
            if (lights[k].component != SG_CACHE_NONE && component[n] == lights[k].component) {
                fwrite(s->nodes[n].position, sizeof(float), 3, out.file);
                fwrite(points + ((size_t)n * light_count + k) * 3, sizeof(float), 3, out.file);
            }
    int32_t e = 0;
    for (uint32_t n = 0; n < s->node_count; n++)
        for (uint32_t k = 0; k < light_count; k++)
            if (lights[k].component != SG_CACHE_NONE && component[n] == lights[k].component) {
                int32_t rec[3] = {2 * e, 2 * e + 1, (int32_t)k};
                fwrite(rec, sizeof rec, 1, out.file);
                e++;
            }
    return sg_output_commit(&out, err);
}

/* ---- the build ---------------------------------------------------------- */

/* Everything one build holds, from the inputs to the file's bytes. */
typedef struct Build {
    const SgMedium *medium;
    const SgSkeleton *skeleton;
    const SgImportanceOptions *options;
    const SgGrid *grid;
    const char *out_path, *mname, *sname;
    uint32_t N, L; /* nodes, lights */
    int threads;
    SgImportanceStats stats;
    /* phases 1 and 2 */
    SgLabelGrid labels;
    SgGraph graph;
    uint32_t *component, *scratch, *pred, *sources;
    double *dist;
    void *heap;
    float *points;
    SgCacheLight *lights;
    SgVisibility vis;
    /* phase 3 */
    BlockPass bp;
    size_t grid_blocks;
    uint16_t *palette_size;
    uint8_t *bits;
    uint64_t block_count, palette_total, bits_total;
    /* phase 4 */
    SgCacheHeader header;
    uint8_t *file;
    size_t file_size;
} Build;

/* Inputs that do not belong together, or that no cache can hold. */
static bool check_inputs(const Build *b, SgError *err)
{
    const SgGrid *grid = b->grid;
    if (b->N == 0)
        return sg_fail(err, "%s: the skeleton has no nodes", b->sname);
    if (grid->nx <= 0 || grid->ny <= 0 || grid->nz <= 0 || !grid->voxels)
        return sg_fail(err, "%s: the medium grid is empty", b->mname);
    for (uint32_t n = 0; n < b->N; n++) {
        const SgSkeletonNode *v = &b->skeleton->nodes[n];
        if (v->kind == SG_NODE_LIGHT && v->light >= 0 && (uint32_t)v->light >= b->L)
            return sg_fail(err, "%s: node %u names light %d but %s has %u lights (they do "
                           "not belong together)", b->sname, n, v->light, b->mname, b->L);
        for (int a = 0; a < 3; a++)
            if (!isfinite(v->position[a]))
                return sg_fail(err, "%s: node %u has a non-finite position", b->sname, n);
    }
    if ((uint64_t)b->N * b->L > (uint64_t)1 << 32)
        return sg_fail(err, "%s: %u nodes x %u lights is too many importance points", b->out_path,
                       b->N, b->L);
    return true;
}

/* 1. Nearest node of every medium voxel. */
static bool label_voxels(Build *b, SgError *err)
{
    bool ok = sg_label_grid_build(b->grid, b->skeleton, b->options->threads, &b->labels, err);
    if (ok) {
        b->stats.medium_voxels = b->labels.medium_voxels;
        b->stats.labelled_voxels = b->labels.labelled_voxels;
        b->stats.label_rounds = b->labels.rounds;
        b->stats.label_settled = b->labels.settled;
    }
    return ok;
}

/* 2a. The graph, its components and the arrays of the shortest paths. */
static bool build_graph(Build *b, SgError *err)
{
    uint32_t N = b->N, L = b->L;
    if (!sg_graph_build(b->skeleton, &b->graph, err))
        return false;
    b->component = malloc((size_t)N * sizeof *b->component);
    b->scratch = malloc((size_t)N * sizeof *b->scratch);
    b->pred = malloc((size_t)N * sizeof *b->pred);
    b->sources = malloc((size_t)N * sizeof *b->sources);
    b->dist = malloc((size_t)N * sizeof *b->dist);
    b->heap = malloc(sg_graph_heap_bytes(&b->graph));
    b->lights = calloc(L ? L : 1, sizeof *b->lights);
    b->points = calloc((size_t)N * L * 3 + 1, sizeof *b->points);
    if (!(b->component && b->scratch && b->pred && b->sources && b->dist && b->heap && b->lights && b->points))
        return sg_fail(err, "%s: out of memory for %u nodes x %u lights", b->out_path, N, L);
    b->stats.components = sg_graph_components(&b->graph, b->component, b->scratch);
    return true;
}

/* The light's nodes, into b->sources: those the skeleton marks with it;
 * failing that, the node nearest to the light's seed voxel. */
static uint32_t light_sources(Build *b, uint32_t k, const double toward_sun[3])
{
    const SgMediumLight *ml = &b->medium->lights[k];
    const SgGrid *grid = b->grid;
    const SgSkeleton *skeleton = b->skeleton;
    uint32_t count = 0;
    for (uint32_t n = 0; n < b->N; n++)
        if ((skeleton->nodes[n].kind == SG_NODE_LIGHT && skeleton->nodes[n].light == (int)k) ||
            (ml->outside && in_margin(grid, b->medium->outside_margin, skeleton->nodes[n].voxel)) ||
            (ml->sun && sunlit(grid, skeleton->nodes[n].voxel, toward_sun)))
            b->sources[count++] = n;
    if (count == 0 && sg_grid_inside(grid, ml->seed[0], ml->seed[1], ml->seed[2])) {
        uint32_t n = sg_label_at(&b->labels, ml->seed[0], ml->seed[1], ml->seed[2]);
        if (n != SG_CACHE_NONE)
            b->sources[count++] = n;
    }
    return count;
}

/* 2b. Light k's entry in the light table and its importance point at every
 * node of its component (shortest paths from its nodes). False when it
 * reaches no node. */
static bool light_points(Build *b, uint32_t k, double tolerance)
{
    const SgMediumLight *ml = &b->medium->lights[k];
    const SgGrid *grid = b->grid;
    SgCacheLight *cl = &b->lights[k];
    for (int a = 0; a < 3; a++)
        cl->position[a] = (float)ml->position[a];
    cl->node = SG_CACHE_NONE;
    cl->component = SG_CACHE_NONE;
    double toward_sun[3] = {-ml->normal[0], -ml->normal[1], -ml->normal[2]};
    uint32_t count = light_sources(b, k, toward_sun);
    if (count == 0)
        return false; /* sealed or outside the medium: reaches no one */
    cl->node = b->sources[0];
    cl->component = b->component[b->sources[0]];
    sg_graph_shortest_paths(&b->graph, b->sources, count, b->dist, b->pred, b->heap);
    double diagonal = grid->voxel_size * sqrt((double)grid->nx * grid->nx + (double)grid->ny * grid->ny +
                                              (double)grid->nz * grid->nz);
    PointPass pp = {&b->vis, b->skeleton, b->component, cl->component, b->pred, b->dist, ml->position,
                    b->points, k, b->L, tolerance, ml->sun ? toward_sun : NULL, diagonal};
    sg_parallel_for((b->N + POINT_CHUNK - 1) / POINT_CHUNK, b->threads, point_chunk, &pp);
    b->stats.lights_reachable++;
    return true;
}

/* 2. Graph, components, the light table and the importance points. */
static bool importance_points(Build *b, bool ok, SgError *err)
{
    if (ok)
        ok = build_graph(b, err);
    double tolerance = b->options->run_tolerance > 0 ? b->options->run_tolerance : 0;
    if (ok)
        ok = sg_visibility_init(&b->vis, b->grid, b->threads, err);
    SgProgress progress;
    sg_progress_begin(&progress, "importance points", b->L);
    for (uint32_t k = 0; ok && k < b->L; k++)
        if (light_points(b, k, tolerance))
            sg_progress_update(&progress, k + 1);
    sg_progress_end(&progress);
    return ok;
}

/* 3. The sparse table: each block's palette size and bits, and the totals. */
static bool count_blocks(Build *b, SgError *err)
{
    const SgGrid *grid = b->grid;
    const int bx = (grid->nx + 7) / 8, by = (grid->ny + 7) / 8, bz = (grid->nz + 7) / 8;
    b->grid_blocks = (size_t)bx * by * bz;
    b->bp = (BlockPass){&b->labels, bx, by, bz, NULL, NULL, NULL, NULL, NULL, NULL};
    b->palette_size = malloc(b->grid_blocks * sizeof *b->palette_size);
    b->bits = malloc(b->grid_blocks);
    if (!b->palette_size || !b->bits)
        return sg_fail(err, "%s: out of memory for the block table", b->out_path);
    b->bp.palette_size = b->palette_size;
    b->bp.bits = b->bits;
    sg_parallel_for((uint64_t)bz, b->threads, block_count_slab, &b->bp);
    for (size_t k = 0; k < b->grid_blocks; k++)
        if (b->palette_size[k]) {
            b->block_count++;
            b->palette_total += b->palette_size[k];
            b->bits_total += (uint64_t)64 * b->bits[k];
        }
    if (b->palette_total > UINT32_MAX || b->bits_total > UINT32_MAX)
        return sg_fail(err, "%s: the nearest-node table is too large", b->out_path);
    return true;
}

/* 4a. The sections' places in the file, and the zeroed file. */
static bool lay_out_file(Build *b, SgError *err)
{
    size_t N = b->N, L = b->L;
    size_t sizes[SG_CACHE_SECTION_COUNT] = {
        [SG_CACHE_NODES] = N * sizeof(SgCacheNode),
        [SG_CACHE_LIGHTS] = L * sizeof(SgCacheLight),
        [SG_CACHE_POINTS] = N * L * 3 * sizeof(float),
        [SG_CACHE_BLOCK_INDEX] = b->grid_blocks * sizeof(uint32_t),
        [SG_CACHE_BLOCKS] = (size_t)b->block_count * sizeof(SgCacheBlock),
        [SG_CACHE_PALETTE] = (size_t)b->palette_total * sizeof(uint32_t),
        [SG_CACHE_VOXEL_BITS] = (size_t)b->bits_total,
    };
    size_t at = align_up(sizeof b->header);
    for (int s = 0; s < SG_CACHE_SECTION_COUNT; s++) {
        b->header.sections[s].offset = at;
        b->header.sections[s].size = sizes[s];
        at = align_up(at + sizes[s]);
    }
    b->file_size = at;
    b->file = calloc(b->file_size, 1);
    bool ok = b->file != NULL;
    if (!ok)
        ok = sg_fail(err, "%s: out of memory for a %zu-byte cache", b->out_path, b->file_size);
    sg_memory_prefer_huge_pages(b->file, b->file_size); /* fewer first-touch faults */
    return ok;
}

/* 4b. The header's fields but the checksum. */
static void fill_header(Build *b)
{
    SgCacheHeader *h = &b->header;
    const SgGrid *grid = b->grid;
    memcpy(h->magic, SG_CACHE_MAGIC, 8);
    h->version = SG_CACHE_VERSION;
    h->header_size = sizeof *h;
    h->file_size = b->file_size;
    h->geometry_hash = b->medium->geometry_hash;
    h->skeleton_hash = sg_importance_skeleton_hash(b->skeleton);
    int32_t dims[3] = {grid->nx, grid->ny, grid->nz};
    uint64_t mh = sg_hash_bytes(SG_HASH_INIT, dims, sizeof dims);
    h->medium_hash = sg_hash_bytes(mh, grid->voxels, sg_grid_count(grid));
    h->nx = grid->nx;
    h->ny = grid->ny;
    h->nz = grid->nz;
    h->block_size = SG_CACHE_BLOCK;
    memcpy(h->origin, grid->origin, sizeof h->origin);
    h->voxel_size = grid->voxel_size;
    h->node_count = b->N;
    h->light_count = b->L;
    h->component_count = b->stats.components;
    h->block_count = (uint32_t)b->block_count;
    h->medium_voxels = b->labels.medium_voxels;
    h->palette_count = b->palette_total;
}

/* 4c. The block index and records (prefix sums of the palettes and bits),
 * then every block's palette and bits, in parallel over slabs. */
static void fill_block_table(Build *b)
{
    uint8_t *file = b->file;
    const SgCacheHeader *h = &b->header;
    uint32_t *block_index = (uint32_t *)(file + h->sections[SG_CACHE_BLOCK_INDEX].offset);
    SgCacheBlock *records = (SgCacheBlock *)(file + h->sections[SG_CACHE_BLOCKS].offset);
    uint32_t record = 0, pal = 0, data = 0;
    for (size_t k = 0; k < b->grid_blocks; k++) {
        if (!b->palette_size[k]) {
            block_index[k] = SG_CACHE_NONE;
            continue;
        }
        block_index[k] = record;
        records[record].palette_offset = pal;
        records[record].data_offset = data;
        records[record].palette_size = b->palette_size[k];
        records[record].bits = b->bits[k];
        pal += b->palette_size[k];
        data += 64u * b->bits[k];
        record++;
    }
    b->bp.block_index = block_index;
    b->bp.records = records;
    b->bp.palette = (uint32_t *)(file + h->sections[SG_CACHE_PALETTE].offset);
    b->bp.voxel_bits = file + h->sections[SG_CACHE_VOXEL_BITS].offset;
    sg_parallel_for((uint64_t)b->bp.bz, b->threads, block_encode_slab, &b->bp);
}

/* 4. Fill the file in memory and checksum it. */
static void fill_file(Build *b)
{
    uint8_t *file = b->file;
    const SgCacheHeader *h = &b->header;
    fill_header(b);
    SgCacheNode *nodes = (SgCacheNode *)(file + h->sections[SG_CACHE_NODES].offset);
    for (uint32_t n = 0; n < b->N; n++) {
        memcpy(nodes[n].position, b->skeleton->nodes[n].position, sizeof nodes[n].position);
        nodes[n].component = b->component[n];
    }
    if (b->L) {
        memcpy(file + h->sections[SG_CACHE_LIGHTS].offset, b->lights, (size_t)b->L * sizeof *b->lights);
        memcpy(file + h->sections[SG_CACHE_POINTS].offset, b->points, (size_t)b->N * b->L * 3 * sizeof(float));
    }
    fill_block_table(b);
    memcpy(file, &b->header, sizeof b->header); /* checksum field still 0 */
    b->header.checksum = sg_hash_bytes(SG_HASH_INIT, file, b->file_size);
    memcpy(file, &b->header, sizeof b->header);
}

/* The side output first: the cache, the target make waits for, appears
 * only when everything succeeded. */
static bool write_outputs(const Build *b, SgError *err)
{
    if (b->options->vectors_path &&
        !write_vectors(b->options->vectors_path, b->skeleton, b->component, b->lights, b->L, b->points, err))
        return false;
    SgOutputFile out;
    if (!sg_output_open(&out, b->out_path, err))
        return false;
    if (fwrite(b->file, 1, b->file_size, out.file) != b->file_size) {
        sg_output_abort(&out);
        return sg_fail(err, "%s: write failed", b->out_path);
    }
    return sg_output_commit(&out, err);
}

static void release_build(Build *b)
{
    free(b->file);
    free(b->palette_size);
    free(b->bits);
    free(b->points);
    free(b->lights);
    free(b->heap);
    free(b->dist);
    free(b->sources);
    free(b->pred);
    free(b->scratch);
    free(b->component);
    sg_visibility_release(&b->vis);
    sg_graph_release(&b->graph);
    sg_label_grid_release(&b->labels);
}

bool sg_importance_build(const SgMedium *medium, const SgSkeleton *skeleton,
                         const SgImportanceOptions *options, const char *out_path,
                         SgImportanceStats *stats_out, SgError *err)
{
    SgImportanceOptions defaults = {0};
    if (!options)
        options = &defaults;
    const double t0 = sg_seconds();
    Build *b = malloc(sizeof *b);
    if (!b)
        return sg_fail(err, "%s: out of memory", out_path);
    *b = (Build){.medium = medium,
                 .skeleton = skeleton,
                 .options = options,
                 .grid = &medium->grid,
                 .out_path = out_path,
                 .mname = options->medium_name ? options->medium_name : "medium",
                 .sname = options->skeleton_name ? options->skeleton_name : "skeleton",
                 .N = skeleton->node_count,
                 .L = medium->light_count};
    if (!check_inputs(b, err)) {
        free(b);
        return false;
    }
    bool ok = label_voxels(b, err);
    b->stats.seconds_labels = sg_seconds() - t0;
    double t1 = sg_seconds();
    b->threads = sg_thread_count(options->threads);
    ok = importance_points(b, ok, err);
    b->stats.seconds_points = sg_seconds() - t1;
    double t2 = sg_seconds();
    ok = ok && count_blocks(b, err) && lay_out_file(b, err);
    if (ok)
        fill_file(b);
    b->stats.seconds_table = sg_seconds() - t2;
    double t3 = sg_seconds();
    ok = ok && write_outputs(b, err);
    b->stats.seconds_write = sg_seconds() - t3;

    SgImportanceStats *stats = &b->stats;
    stats->nodes = b->N;
    stats->lights = b->L;
    stats->blocks = b->block_count;
    stats->palette_entries = b->palette_total;
    stats->bytes = b->file_size;
    stats->seconds_total = sg_seconds() - t0;
    if (stats_out)
        *stats_out = *stats;
    release_build(b);
    free(b);
    return ok;
}
