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
    if (!sg_output_open(&out, path, err))
        return false;
    fprintf(out.file,
            "ply\nformat binary_little_endian 1.0\n"
            "comment importance points (Biri & Chaussard 2012, figure 2): one edge per node and "
            "light, from the node to its importance point\n"
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

bool sg_importance_build(const SgMedium *medium, const SgSkeleton *skeleton,
                         const SgImportanceOptions *options, const char *out_path,
                         SgImportanceStats *stats_out, SgError *err)
{
    SgImportanceOptions defaults = {0};
    if (!options)
        options = &defaults;
    SgImportanceStats stats;
    memset(&stats, 0, sizeof stats);
    const SgGrid *grid = &medium->grid;
    const double t0 = sg_seconds();
    const uint32_t N = skeleton->node_count, L = medium->light_count;
    const char *mname = options->medium_name ? options->medium_name : "medium";
    const char *sname = options->skeleton_name ? options->skeleton_name : "skeleton";

    if (N == 0)
        return sg_fail(err, "%s: the skeleton has no nodes", sname);
    if (grid->nx <= 0 || grid->ny <= 0 || grid->nz <= 0 || !grid->voxels)
        return sg_fail(err, "%s: the medium grid is empty", mname);
    for (uint32_t n = 0; n < N; n++) {
        const SgSkeletonNode *v = &skeleton->nodes[n];
        if (v->kind == SG_NODE_LIGHT && v->light >= 0 && (uint32_t)v->light >= L)
            return sg_fail(err, "%s: node %u names light %d but %s has %u lights (they do "
                           "not belong together)", sname, n, v->light, mname, L);
        for (int a = 0; a < 3; a++)
            if (!isfinite(v->position[a]))
                return sg_fail(err, "%s: node %u has a non-finite position", sname, n);
    }
    if ((uint64_t)N * L > (uint64_t)1 << 32)
        return sg_fail(err, "%s: %u nodes x %u lights is too many importance points", out_path,
                       N, L);

    bool ok = true;
    SgLabelGrid labels = {0};
    SgGraph graph = {0};
    uint32_t *component = NULL, *scratch = NULL, *pred = NULL, *sources = NULL;
    double *dist = NULL;
    void *heap = NULL;
    float *points = NULL;
    SgCacheLight *lights = NULL;
    uint16_t *palette_size = NULL;
    uint8_t *bits = NULL;
    uint8_t *file = NULL;

    /* 1. Nearest node of every medium voxel. */
    ok = sg_label_grid_build(grid, skeleton, options->threads, &labels, err);
    stats.seconds_labels = sg_seconds() - t0;
    if (ok) {
        stats.medium_voxels = labels.medium_voxels;
        stats.labelled_voxels = labels.labelled_voxels;
        stats.label_rounds = labels.rounds;
        stats.label_settled = labels.settled;
    }

    /* 2. Graph, components, the light table. */
    double t1 = sg_seconds();
    if (ok)
        ok = sg_graph_build(skeleton, &graph, err);
    if (ok) {
        component = malloc((size_t)N * sizeof *component);
        scratch = malloc((size_t)N * sizeof *scratch);
        pred = malloc((size_t)N * sizeof *pred);
        sources = malloc((size_t)N * sizeof *sources);
        dist = malloc((size_t)N * sizeof *dist);
        heap = malloc(sg_graph_heap_bytes(&graph));
        lights = calloc(L ? L : 1, sizeof *lights);
        points = calloc((size_t)N * L * 3 + 1, sizeof *points);
        ok = component && scratch && pred && sources && dist && heap && lights && points;
        if (!ok)
            sg_fail(err, "%s: out of memory for %u nodes x %u lights", out_path, N, L);
    }
    if (ok)
        stats.components = sg_graph_components(&graph, component, scratch);

    int threads = sg_thread_count(options->threads);
    double tolerance = options->run_tolerance > 0 ? options->run_tolerance : 0;
    SgVisibility vis = {0};
    if (ok)
        ok = sg_visibility_init(&vis, grid, threads, err);
    SgProgress progress;
    sg_progress_begin(&progress, "importance points", L);
    for (uint32_t k = 0; ok && k < L; k++) {
        const SgMediumLight *ml = &medium->lights[k];
        SgCacheLight *cl = &lights[k];
        for (int a = 0; a < 3; a++)
            cl->position[a] = (float)ml->position[a];
        cl->node = SG_CACHE_NONE;
        cl->component = SG_CACHE_NONE;
        /* The light's nodes: those the skeleton marks with it; failing
         * that, the node nearest to the light's seed voxel. */
        uint32_t count = 0;
        double toward_sun[3] = {-ml->normal[0], -ml->normal[1], -ml->normal[2]};
        for (uint32_t n = 0; n < N; n++)
            if ((skeleton->nodes[n].kind == SG_NODE_LIGHT && skeleton->nodes[n].light == (int)k) ||
                (ml->outside && in_margin(grid, medium->outside_margin, skeleton->nodes[n].voxel)) ||
                (ml->sun && sunlit(grid, skeleton->nodes[n].voxel, toward_sun)))
                sources[count++] = n;
        if (count == 0 && sg_grid_inside(grid, ml->seed[0], ml->seed[1], ml->seed[2])) {
            uint32_t n = sg_label_at(&labels, ml->seed[0], ml->seed[1], ml->seed[2]);
            if (n != SG_CACHE_NONE)
                sources[count++] = n;
        }
        if (count == 0)
            continue; /* sealed or outside the medium: reaches no one */
        cl->node = sources[0];
        cl->component = component[sources[0]];
        sg_graph_shortest_paths(&graph, sources, count, dist, pred, heap);
        double diagonal = grid->voxel_size * sqrt((double)grid->nx * grid->nx + (double)grid->ny * grid->ny +
                                                  (double)grid->nz * grid->nz);
        PointPass pp = {&vis, skeleton, component, cl->component, pred, dist, ml->position,
                        points, k, L, tolerance, ml->sun ? toward_sun : NULL, diagonal};
        sg_parallel_for((N + POINT_CHUNK - 1) / POINT_CHUNK, threads, point_chunk, &pp);
        stats.lights_reachable++;
        sg_progress_update(&progress, k + 1);
    }
    sg_progress_end(&progress);
    stats.seconds_points = sg_seconds() - t1;

    /* 3. The sparse table. */
    double t2 = sg_seconds();
    const int bx = (grid->nx + 7) / 8, by = (grid->ny + 7) / 8, bz = (grid->nz + 7) / 8;
    const size_t grid_blocks = (size_t)bx * by * bz;
    BlockPass bp = {&labels, bx, by, bz, NULL, NULL, NULL, NULL, NULL, NULL};
    uint32_t *block_index = NULL;
    uint64_t block_count = 0, palette_total = 0, bits_total = 0;
    if (ok) {
        palette_size = malloc(grid_blocks * sizeof *palette_size);
        bits = malloc(grid_blocks);
        ok = palette_size && bits;
        if (!ok)
            sg_fail(err, "%s: out of memory for the block table", out_path);
    }
    if (ok) {
        bp.palette_size = palette_size;
        bp.bits = bits;
        sg_parallel_for((uint64_t)bz, threads, block_count_slab, &bp);
        for (size_t b = 0; b < grid_blocks; b++)
            if (palette_size[b]) {
                block_count++;
                palette_total += palette_size[b];
                bits_total += (uint64_t)64 * bits[b];
            }
        if (palette_total > UINT32_MAX || bits_total > UINT32_MAX)
            ok = sg_fail(err, "%s: the nearest-node table is too large", out_path);
    }

    /* 4. Lay out the file in memory, fill, checksum, write. */
    SgCacheHeader header;
    memset(&header, 0, sizeof header);
    size_t file_size = 0;
    if (ok) {
        size_t sizes[SG_CACHE_SECTION_COUNT] = {
            [SG_CACHE_NODES] = (size_t)N * sizeof(SgCacheNode),
            [SG_CACHE_LIGHTS] = (size_t)L * sizeof(SgCacheLight),
            [SG_CACHE_POINTS] = (size_t)N * L * 3 * sizeof(float),
            [SG_CACHE_BLOCK_INDEX] = grid_blocks * sizeof(uint32_t),
            [SG_CACHE_BLOCKS] = (size_t)block_count * sizeof(SgCacheBlock),
            [SG_CACHE_PALETTE] = (size_t)palette_total * sizeof(uint32_t),
            [SG_CACHE_VOXEL_BITS] = (size_t)bits_total,
        };
        size_t at = align_up(sizeof header);
        for (int s = 0; s < SG_CACHE_SECTION_COUNT; s++) {
            header.sections[s].offset = at;
            header.sections[s].size = sizes[s];
            at = align_up(at + sizes[s]);
        }
        file_size = at;
        file = calloc(file_size, 1);
        if (!file)
            ok = sg_fail(err, "%s: out of memory for a %zu-byte cache", out_path, file_size);
        sg_memory_prefer_huge_pages(file, file_size); /* fewer first-touch faults */
    }
    if (ok) {
        memcpy(header.magic, SG_CACHE_MAGIC, 8);
        header.version = SG_CACHE_VERSION;
        header.header_size = sizeof header;
        header.file_size = file_size;
        header.geometry_hash = medium->geometry_hash;
        header.skeleton_hash = sg_importance_skeleton_hash(skeleton);
        int32_t dims[3] = {grid->nx, grid->ny, grid->nz};
        uint64_t mh = sg_hash_bytes(SG_HASH_INIT, dims, sizeof dims);
        header.medium_hash = sg_hash_bytes(mh, grid->voxels, sg_grid_count(grid));
        header.nx = grid->nx;
        header.ny = grid->ny;
        header.nz = grid->nz;
        header.block_size = SG_CACHE_BLOCK;
        memcpy(header.origin, grid->origin, sizeof header.origin);
        header.voxel_size = grid->voxel_size;
        header.node_count = N;
        header.light_count = L;
        header.component_count = stats.components;
        header.block_count = (uint32_t)block_count;
        header.medium_voxels = labels.medium_voxels;
        header.palette_count = palette_total;

        SgCacheNode *nodes = (SgCacheNode *)(file + header.sections[SG_CACHE_NODES].offset);
        for (uint32_t n = 0; n < N; n++) {
            memcpy(nodes[n].position, skeleton->nodes[n].position, sizeof nodes[n].position);
            nodes[n].component = component[n];
        }
        if (L) {
            memcpy(file + header.sections[SG_CACHE_LIGHTS].offset, lights,
                   (size_t)L * sizeof *lights);
            memcpy(file + header.sections[SG_CACHE_POINTS].offset, points,
                   (size_t)N * L * 3 * sizeof(float));
        }
        block_index = (uint32_t *)(file + header.sections[SG_CACHE_BLOCK_INDEX].offset);
        SgCacheBlock *records = (SgCacheBlock *)(file + header.sections[SG_CACHE_BLOCKS].offset);
        uint32_t record = 0, pal = 0, data = 0;
        for (size_t b = 0; b < grid_blocks; b++) {
            if (!palette_size[b]) {
                block_index[b] = SG_CACHE_NONE;
                continue;
            }
            block_index[b] = record;
            records[record].palette_offset = pal;
            records[record].data_offset = data;
            records[record].palette_size = palette_size[b];
            records[record].bits = bits[b];
            pal += palette_size[b];
            data += 64u * bits[b];
            record++;
        }
        bp.block_index = block_index;
        bp.records = records;
        bp.palette = (uint32_t *)(file + header.sections[SG_CACHE_PALETTE].offset);
        bp.voxel_bits = file + header.sections[SG_CACHE_VOXEL_BITS].offset;
        sg_parallel_for((uint64_t)bz, threads, block_encode_slab, &bp);

        memcpy(file, &header, sizeof header); /* checksum field still 0 */
        header.checksum = sg_hash_bytes(SG_HASH_INIT, file, file_size);
        memcpy(file, &header, sizeof header);
    }
    stats.seconds_table = sg_seconds() - t2;
    double t3 = sg_seconds();
    /* The side output first: the cache, the target make waits for, appears
     * only when everything succeeded. */
    if (ok && options->vectors_path)
        ok = write_vectors(options->vectors_path, skeleton, component, lights, L, points, err);
    if (ok) {
        SgOutputFile out;
        ok = sg_output_open(&out, out_path, err);
        if (ok) {
            if (fwrite(file, 1, file_size, out.file) != file_size) {
                sg_output_abort(&out);
                ok = sg_fail(err, "%s: write failed", out_path);
            } else {
                ok = sg_output_commit(&out, err);
            }
        }
    }
    stats.seconds_write = sg_seconds() - t3;

    stats.nodes = N;
    stats.lights = L;
    stats.blocks = block_count;
    stats.palette_entries = palette_total;
    stats.bytes = file_size;
    stats.seconds_total = sg_seconds() - t0;
    if (stats_out)
        *stats_out = stats;

    free(file);
    free(palette_size);
    free(bits);
    free(points);
    free(lights);
    free(heap);
    free(dist);
    free(sources);
    free(pred);
    free(scratch);
    free(component);
    sg_visibility_release(&vis);
    sg_graph_release(&graph);
    sg_label_grid_release(&labels);
    return ok;
}
