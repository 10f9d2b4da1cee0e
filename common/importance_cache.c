/* Reader of importance.cache: maps the file, validates it once (size,
 * magic, version, checksum, every offset and index), then answers lookups
 * in constant time straight from the mapping. Layout: importance_cache_format.h
 * and docs/cache-format.md. */
#include "importance_cache.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "hash.h"
#include "importance_cache_format.h"

_Static_assert((SG_CACHE_NONE & SG_CACHE_WALL_BIT) != 0, "'none' reads as a wall entry");

struct SgImportanceCache {
    const uint8_t *data;
    size_t size;
    bool mapped; /* data is our mmap (else memory the caller owns) */
    SgCacheHeader header;
    const SgCacheNode *nodes;
    const SgCacheLight *lights;
    const float *points;
    const uint32_t *block_index;
    const SgCacheBlock *blocks;
    const uint32_t *palette;
    const uint8_t *voxel_bits;
    uint64_t voxel_bits_size;
    int bx, by, bz;
    double inv_voxel_size;
    bool one_component; /* every node in one component: no need to read the node */
    uint32_t *decoded;  /* sg_cache_decode: node per voxel, x fastest; NULL: read the blocks */
    uint32_t *octants;  /* sg_cache_decode: 8 per mixed wall voxel (sg_cache_decoded_octants) */
};

static bool range_ok(const SgCacheRange *r, uint64_t header_size, uint64_t file_size)
{
    return r->offset % SG_CACHE_ALIGN == 0 && r->offset >= header_size &&
           r->offset <= file_size && r->size <= file_size - r->offset;
}

/* The header: magic, version, size, checksum of the whole file (with the
 * checksum field read as zero). */
static bool validate_header(SgImportanceCache *c, const char *name, SgError *err)
{
    if (c->size < sizeof(SgCacheHeader))
        return sg_fail(err, "%s: truncated: %zu bytes, smaller than the cache header", name, c->size);
    SgCacheHeader *h = &c->header;
    memcpy(h, c->data, sizeof *h);
    if (memcmp(h->magic, SG_CACHE_MAGIC, 8) != 0)
        return sg_fail(err, "%s: not an importance cache (wrong magic)", name);
    if (h->version != SG_CACHE_VERSION)
        return sg_fail(err, "%s: cache version %u, this program reads version %u (rebuild it "
                       "with bin/importance)", name, h->version, SG_CACHE_VERSION);
    if (h->header_size != sizeof *h)
        return sg_fail(err, "%s: header size %u, expected %zu", name, h->header_size, sizeof *h);
    if (h->file_size != c->size)
        return sg_fail(err, "%s: %s: the header says %llu bytes, the file has %zu", name,
                       h->file_size > c->size ? "truncated" : "trailing bytes", (unsigned long long)h->file_size,
                       c->size);
    SgCacheHeader zeroed = *h;
    zeroed.checksum = 0;
    uint64_t sum = sg_hash_bytes(SG_HASH_INIT, &zeroed, sizeof zeroed);
    sum = sg_hash_bytes(sum, c->data + sizeof zeroed, c->size - sizeof zeroed);
    if (sum != h->checksum)
        return sg_fail(err, "%s: checksum mismatch (the file is corrupted)", name);
    return true;
}

/* The grid's size, transform and blocks per axis. */
static bool validate_grid(SgImportanceCache *c, const char *name, SgError *err)
{
    const SgCacheHeader *h = &c->header;
    if (h->nx <= 0 || h->ny <= 0 || h->nz <= 0 || h->nx > (1 << 20) || h->ny > (1 << 20) || h->nz > (1 << 20) ||
        h->block_size != SG_CACHE_BLOCK)
        return sg_fail(err, "%s: bad grid size %dx%dx%d (block %d)", name, h->nx, h->ny, h->nz, h->block_size);
    if (!(h->voxel_size > 0) || !isfinite(h->voxel_size) || !isfinite(h->origin[0]) || !isfinite(h->origin[1]) ||
        !isfinite(h->origin[2]))
        return sg_fail(err, "%s: bad grid transform", name);
    c->bx = (h->nx + 7) / 8;
    c->by = (h->ny + 7) / 8;
    c->bz = (h->nz + 7) / 8;
    if ((uint64_t)c->bx * c->by * c->bz > UINT32_MAX)
        return sg_fail(err, "%s: grid too large", name);
    if (h->medium_voxels > (uint64_t)h->nx * h->ny * h->nz)
        return sg_fail(err, "%s: more medium voxels than voxels", name);
    return true;
}

/* Every section in the file with the size its counts imply; the pointers
 * into them. Products cannot overflow 64 bits since each count is at most
 * 32 bits and the sizes are small constants. */
static bool validate_sections(SgImportanceCache *c, const char *name, SgError *err)
{
    static const char *const section_names[SG_CACHE_SECTION_COUNT] = {
        "nodes", "lights", "points", "block index", "blocks", "palette", "voxel bits"};
    const SgCacheHeader *h = &c->header;
    uint64_t points = (uint64_t)h->node_count * h->light_count;
    if (h->light_count && points / h->light_count != h->node_count)
        return sg_fail(err, "%s: node and light counts overflow", name);
    uint64_t expected[SG_CACHE_SECTION_COUNT] = {
        [SG_CACHE_NODES] = (uint64_t)h->node_count * sizeof(SgCacheNode),
        [SG_CACHE_LIGHTS] = (uint64_t)h->light_count * sizeof(SgCacheLight),
        [SG_CACHE_POINTS] = points > UINT64_MAX / 12 ? UINT64_MAX : points * 12,
        [SG_CACHE_BLOCK_INDEX] = (uint64_t)c->bx * c->by * c->bz * 4,
        [SG_CACHE_BLOCKS] = (uint64_t)h->block_count * sizeof(SgCacheBlock),
        [SG_CACHE_PALETTE] = h->palette_count > UINT64_MAX / 4 ? UINT64_MAX : h->palette_count * 4,
        [SG_CACHE_VOXEL_BITS] = h->sections[SG_CACHE_VOXEL_BITS].size,
    };
    for (int s = 0; s < SG_CACHE_SECTION_COUNT; s++) {
        if (!range_ok(&h->sections[s], sizeof *h, c->size))
            return sg_fail(err, "%s: %s section out of range (offset %llu, size %llu, file %zu)", name,
                           section_names[s], (unsigned long long)h->sections[s].offset,
                           (unsigned long long)h->sections[s].size, c->size);
        if (h->sections[s].size != expected[s])
            return sg_fail(err, "%s: %s section has %llu bytes, expected %llu", name, section_names[s],
                           (unsigned long long)h->sections[s].size, (unsigned long long)expected[s]);
    }
    if (h->node_count == 0)
        return sg_fail(err, "%s: no skeleton nodes", name);
    c->nodes = (const SgCacheNode *)(c->data + h->sections[SG_CACHE_NODES].offset);
    c->lights = (const SgCacheLight *)(c->data + h->sections[SG_CACHE_LIGHTS].offset);
    c->points = (const float *)(c->data + h->sections[SG_CACHE_POINTS].offset);
    c->block_index = (const uint32_t *)(c->data + h->sections[SG_CACHE_BLOCK_INDEX].offset);
    c->blocks = (const SgCacheBlock *)(c->data + h->sections[SG_CACHE_BLOCKS].offset);
    c->palette = (const uint32_t *)(c->data + h->sections[SG_CACHE_PALETTE].offset);
    c->voxel_bits = c->data + h->sections[SG_CACHE_VOXEL_BITS].offset;
    c->voxel_bits_size = h->sections[SG_CACHE_VOXEL_BITS].size;
    return true;
}

/* Nodes, lights and importance points: components in range, positions finite. */
static bool validate_graph(const SgImportanceCache *c, const char *name, SgError *err)
{
    const SgCacheHeader *h = &c->header;
    for (uint32_t n = 0; n < h->node_count; n++) {
        const SgCacheNode *v = &c->nodes[n];
        if (v->component >= h->component_count || !isfinite(v->position[0]) || !isfinite(v->position[1]) ||
            !isfinite(v->position[2]))
            return sg_fail(err, "%s: node %u is invalid", name, n);
    }
    for (uint32_t k = 0; k < h->light_count; k++) {
        const SgCacheLight *l = &c->lights[k];
        bool none = l->component == SG_CACHE_NONE;
        if ((none != (l->node == SG_CACHE_NONE)) ||
            (!none && (l->node >= h->node_count || l->component >= h->component_count ||
                       c->nodes[l->node].component != l->component)) ||
            !isfinite(l->position[0]) || !isfinite(l->position[1]) || !isfinite(l->position[2]))
            return sg_fail(err, "%s: light %u is invalid", name, k);
    }
    uint64_t points = (uint64_t)h->node_count * h->light_count;
    for (uint64_t i = 0; i < points * 3; i++)
        if (!isfinite(c->points[i]))
            return sg_fail(err, "%s: importance point %llu is not finite", name, (unsigned long long)(i / 3));
    return true;
}

/* The nearest-node table: block index, block records, palette. */
static bool validate_table(const SgImportanceCache *c, const char *name, SgError *err)
{
    const SgCacheHeader *h = &c->header;
    const uint64_t grid_blocks = (uint64_t)c->bx * c->by * c->bz;
    for (uint64_t b = 0; b < grid_blocks; b++)
        if (c->block_index[b] != SG_CACHE_NONE && c->block_index[b] >= h->block_count)
            return sg_fail(err, "%s: block index entry %llu out of range", name, (unsigned long long)b);
    for (uint32_t b = 0; b < h->block_count; b++) {
        const SgCacheBlock *r = &c->blocks[b];
        unsigned bits = r->bits;
        uint64_t capacity = bits == 0 ? 1 : bits >= 9 ? 512 : (1u << bits);
        if ((bits != 0 && bits != 1 && bits != 2 && bits != 4 && bits != 8 && bits != 16) ||
            r->palette_size == 0 || r->palette_size > capacity ||
            (uint64_t)r->palette_offset + r->palette_size > h->palette_count ||
            (uint64_t)r->data_offset + 64u * bits > c->voxel_bits_size)
            return sg_fail(err, "%s: block record %u is invalid", name, b);
    }
    for (uint64_t p = 0; p < h->palette_count; p++)
        if (c->palette[p] != SG_CACHE_NONE && c->palette[p] >= h->node_count)
            return sg_fail(err, "%s: palette entry %llu names a missing node", name, (unsigned long long)p);
    return true;
}

/* Every index that a lookup follows is checked here once. */
static bool validate(SgImportanceCache *c, const char *name, SgError *err)
{
    return validate_header(c, name, err) && validate_grid(c, name, err) && validate_sections(c, name, err) &&
           validate_graph(c, name, err) && validate_table(c, name, err);
}

SgImportanceCache *sg_cache_open_memory(const void *data, size_t size, const char *name,
                                        SgError *err)
{
    SgImportanceCache *c = calloc(1, sizeof *c);
    if (!c) {
        sg_fail(err, "%s: out of memory", name);
        return NULL;
    }
    c->data = data;
    c->size = size;
    if (((uintptr_t)data % SG_CACHE_ALIGN) != 0) {
        sg_fail(err, "%s: cache memory is not %d-byte aligned", name, SG_CACHE_ALIGN);
        free(c);
        return NULL;
    }
    if (!validate(c, name, err)) {
        free(c);
        return NULL;
    }
    c->inv_voxel_size = 1.0 / c->header.voxel_size;
    c->one_component = c->header.component_count == 1;
    return c;
}

SgImportanceCache *sg_cache_open(const char *path, SgError *err)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0) {
        sg_fail(err, "%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        sg_fail(err, "%s: not a regular file", path);
        close(fd);
        return NULL;
    }
    size_t size = (size_t)st.st_size;
    if (size < sizeof(SgCacheHeader)) {
        sg_fail(err, "%s: truncated: %zu bytes, smaller than the cache header", path, size);
        close(fd);
        return NULL;
    }
    void *map = mmap(NULL, size, PROT_READ, MAP_PRIVATE, fd, 0);
    int e = errno;
    close(fd);
    if (map == MAP_FAILED) {
        sg_fail(err, "%s: cannot map: %s", path, strerror(e));
        return NULL;
    }
    SgImportanceCache *c = sg_cache_open_memory(map, size, path, err);
    if (!c) {
        munmap(map, size);
        return NULL;
    }
    c->mapped = true;
    return c;
}

void sg_cache_close(SgImportanceCache *cache)
{
    if (!cache)
        return;
    if (cache->mapped)
        munmap((void *)cache->data, cache->size);
    free(cache->decoded);
    free(cache->octants);
    free(cache);
}

uint64_t sg_cache_geometry_hash(const SgImportanceCache *c) { return c->header.geometry_hash; }
uint64_t sg_cache_skeleton_hash(const SgImportanceCache *c) { return c->header.skeleton_hash; }
uint64_t sg_cache_checksum(const SgImportanceCache *c) { return c->header.checksum; }
uint32_t sg_cache_light_count(const SgImportanceCache *c) { return c->header.light_count; }
uint32_t sg_cache_node_count(const SgImportanceCache *c) { return c->header.node_count; }
uint32_t sg_cache_component_count(const SgImportanceCache *c) { return c->header.component_count; }
uint64_t sg_cache_medium_voxels(const SgImportanceCache *c) { return c->header.medium_voxels; }
uint64_t sg_cache_bytes(const SgImportanceCache *c) { return c->size; }
double sg_cache_voxel_size(const SgImportanceCache *c) { return c->header.voxel_size; }

void sg_cache_grid(const SgImportanceCache *c, int dims[3], double origin[3])
{
    dims[0] = c->header.nx;
    dims[1] = c->header.ny;
    dims[2] = c->header.nz;
    memcpy(origin, c->header.origin, sizeof c->header.origin);
}

bool sg_cache_light_has_paths(const SgImportanceCache *c, uint32_t light)
{
    return light < c->header.light_count && c->lights[light].component != SG_CACHE_NONE;
}

/* Index of voxel (i,j,k) in a table of the grid, x fastest (the decoded table). */
static inline size_t grid_index(int nx, int ny, int i, int j, int k)
{
    return (size_t)i + (size_t)nx * ((size_t)j + (size_t)ny * (size_t)k);
}

/* One unsigned comparison per axis also rejects negative indices. */
static inline bool in_grid(const SgImportanceCache *c, int i, int j, int k)
{
    return (unsigned)i < (unsigned)c->header.nx && (unsigned)j < (unsigned)c->header.ny &&
           (unsigned)k < (unsigned)c->header.nz;
}

/* Node of voxel (i,j,k) inside the grid, read from its packed block. */
static uint32_t packed_voxel_node(const SgImportanceCache *c, int i, int j, int k)
{
    size_t b = (size_t)(i >> 3) + (size_t)c->bx * ((size_t)(j >> 3) + (size_t)c->by * (size_t)(k >> 3));
    uint32_t record = c->block_index[b];
    if (record == SG_CACHE_NONE)
        return SG_CACHE_NONE;
    const SgCacheBlock *r = &c->blocks[record];
    unsigned local = (unsigned)((i & 7) | (j & 7) << 3 | (k & 7) << 6);
    unsigned index = 0;
    const uint8_t *data = c->voxel_bits + r->data_offset;
    if (r->bits == 16) {
        index = data[2 * local] | (unsigned)data[2 * local + 1] << 8;
    } else if (r->bits) {
        unsigned bit = local * r->bits;
        index = (data[bit >> 3] >> (bit & 7)) & ((1u << r->bits) - 1);
    }
    if (index >= r->palette_size) /* validated blocks keep this in range; cheap insurance */
        return SG_CACHE_NONE;
    return c->palette[r->palette_offset + index];
}

/* Nearest node of voxel (i,j,k), SG_CACHE_NONE if not medium. */
static inline uint32_t voxel_node(const SgImportanceCache *c, int i, int j, int k)
{
    if (!in_grid(c, i, j, k))
        return SG_CACHE_NONE;
    if (c->decoded) {
        uint32_t m = c->decoded[grid_index(c->header.nx, c->header.ny, i, j, k)];
        return m & SG_CACHE_WALL_BIT ? SG_CACHE_NONE : m; /* a wall's entry is not medium */
    }
    return packed_voxel_node(c, i, j, k);
}

/* The order of a wall's neighbours as seen from each octant of it (octant_node). */
typedef struct OctantOrder {
    uint8_t at[8][27]; /* octant o's neighbour of rank cell r (x's rank slowest): its index in around[] */
    uint32_t beyond[27]; /* rank cells no earlier on any axis than r, r excluded */
} OctantOrder;

static void octant_order(OctantOrder *ord)
{
    for (int r = 0; r < 27; r++) {
        int rank[3] = {r / 9, r / 3 % 3, r % 3};
        ord->beyond[r] = 0;
        for (int q = 0; q < 27; q++)
            if (q != r && q / 9 >= rank[0] && q / 3 % 3 >= rank[1] && q % 3 >= rank[2])
                ord->beyond[r] |= 1u << q;
        for (unsigned o = 0; o < 8; o++) {
            int index = 0, scale[3] = {1, 3, 9};
            for (int a = 0; a < 3; a++) {
                int toward = o >> a & 1 ? 1 : -1;
                int step = rank[a] == 0 ? 0 : rank[a] == 1 ? toward : -toward;
                index += (step + 1) * scale[a];
            }
            ord->at[o][r] = (uint8_t)index;
        }
    }
}

/* The answer of neighbour_node for every point in one octant of a wall
 * voxel, if there is one (octant bit a set where the point's coordinate a
 * is at least the voxel's centre). Per axis a neighbour's offset is 0,
 * toward the octant (near) or away (far), its rank 0, 1, 2: in the octant
 * the squared distances along the axis keep that order (f^2 <= (1-|f|)^2
 * <= (1+|f|)^2 for |f| <= 1/2). So a medium neighbour no later on any
 * axis than another is never farther from any point: the search returns a
 * neighbour that no other dominates so (of equal distances it keeps the
 * first, in rank order), and when all those have one node, every point of
 * the octant gets it. From the entries of the 3x3x3 voxels around the
 * wall (x fastest; SG_CACHE_WALL_BIT set where solid or outside the grid).
 * SG_CACHE_NONE: they disagree (search), or no neighbour is medium. */
static uint32_t octant_node(const OctantOrder *ord, const uint32_t around[27], unsigned octant)
{
    uint32_t medium = 0, dominated = 0;
    for (int r = 0; r < 27; r++)
        if (!(around[ord->at[octant][r]] & SG_CACHE_WALL_BIT)) { /* medium (never the voxel itself) */
            medium |= 1u << r;
            dominated |= ord->beyond[r];
        }
    uint32_t common = SG_CACHE_NONE;
    for (uint32_t first = medium & ~dominated; first; first &= first - 1) {
        uint32_t m = around[ord->at[octant][__builtin_ctz(first)]];
        if (common != SG_CACHE_NONE && m != common)
            return SG_CACHE_NONE;
        common = m;
    }
    return common;
}

bool sg_cache_decode(SgImportanceCache *c, uint64_t max_bytes)
{
    if (c->decoded)
        return true;
    const int nx = c->header.nx, ny = c->header.ny, nz = c->header.nz;
    uint64_t voxels = (uint64_t)nx * (uint64_t)ny * (uint64_t)nz;
    if (voxels * sizeof(uint32_t) > max_bytes)
        return false;
    uint32_t *t = malloc(voxels * sizeof *t);
    if (!t)
        return false;
    /* block by block: an absent block fills its voxels at once */
    for (int bk = 0; bk < c->bz; bk++)
        for (int bj = 0; bj < c->by; bj++)
            for (int bi = 0; bi < c->bx; bi++) {
                bool present = c->block_index[bi + (size_t)c->bx * (bj + (size_t)c->by * bk)] != SG_CACHE_NONE;
                for (int k = 8 * bk; k < 8 * bk + 8 && k < nz; k++)
                    for (int j = 8 * bj; j < 8 * bj + 8 && j < ny; j++)
                        for (int i = 8 * bi; i < 8 * bi + 8 && i < nx; i++)
                            t[grid_index(nx, ny, i, j, k)] =
                                present ? packed_voxel_node(c, i, j, k) : SG_CACHE_NONE;
            }
    /* A wall voxel whose medium neighbours (of 26) all have one node: any
     * point in it gets that node (neighbour_node could pick no other), so
     * the entry says so and a lookup there needs no search. Where they
     * disagree (next to an edge of the skeleton's regions), each octant of
     * the voxel usually still has one answer (octant_node): the entry then
     * points to the voxel's eight. */
    uint32_t *octants = NULL;
    size_t mixed = 0, capacity = 0;
    OctantOrder order;
    octant_order(&order);
    if (c->header.node_count < SG_CACHE_MIXED_BIT)
        for (int k = 0; k < nz; k++)
            for (int j = 0; j < ny; j++)
                for (int i = 0; i < nx; i++) {
                    size_t at = grid_index(nx, ny, i, j, k);
                    if (t[at] != SG_CACHE_NONE)
                        continue;
                    uint32_t around[27]; /* the 3x3x3 voxels, x fastest; SG_CACHE_NONE outside */
                    for (int dz = -1; dz <= 1; dz++)
                        for (int dy = -1; dy <= 1; dy++) {
                            uint32_t *row = around + 3 * (dy + 1) + 9 * (dz + 1);
                            int b = j + dy, e = k + dz;
                            if ((unsigned)b >= (unsigned)ny || (unsigned)e >= (unsigned)nz) {
                                row[0] = row[1] = row[2] = SG_CACHE_NONE;
                                continue;
                            }
                            const uint32_t *x = t + grid_index(nx, ny, i, b, e);
                            row[0] = i > 0 ? x[-1] : SG_CACHE_NONE;
                            row[1] = x[0];
                            row[2] = i + 1 < nx ? x[1] : SG_CACHE_NONE;
                        }
                    uint32_t common = SG_CACHE_NONE;
                    bool is_mixed = false;
                    for (int q = 0; q < 27 && !is_mixed; q++) {
                        if (around[q] & SG_CACHE_WALL_BIT)
                            continue; /* solid (maybe marked already), outside, or the voxel itself */
                        is_mixed = common != SG_CACHE_NONE && around[q] != common;
                        common = around[q];
                    }
                    if (!is_mixed) {
                        if (common != SG_CACHE_NONE)
                            t[at] = common | SG_CACHE_WALL_BIT;
                        continue;
                    }
                    if (mixed >= SG_CACHE_MIXED_INDEX)
                        continue; /* no index left: the search answers */
                    if (mixed == capacity) {
                        size_t grown = capacity ? 2 * capacity : 1024;
                        uint32_t *more = realloc(octants, grown * 8 * sizeof *more);
                        if (!more)
                            continue; /* no memory: the search answers */
                        octants = more;
                        capacity = grown;
                    }
                    for (unsigned o = 0; o < 8; o++)
                        octants[8 * mixed + o] = octant_node(&order, around, o);
                    t[at] = SG_CACHE_WALL_BIT | SG_CACHE_MIXED_BIT | (uint32_t)mixed++;
                }
    c->decoded = t;
    c->octants = octants;
    return true;
}

/* Voxel indices of v (voxel units), false outside the range any grid can
 * have; NaN fails too. */
static inline bool voxel_of(const double v[3], int ijk[3])
{
    for (int a = 0; a < 3; a++) {
        if (!(v[a] > -2.0 && v[a] < (double)(1 << 21)))
            return false;
        int i = (int)v[a]; /* floor without the libm call: v > -2 */
        ijk[a] = i - (v[a] < (double)i);
    }
    return true;
}

const uint32_t *sg_cache_decoded(const SgImportanceCache *c) { return c->decoded; }
const uint32_t *sg_cache_decoded_octants(const SgImportanceCache *c) { return c->octants; }

/* A surface point lies in a solid voxel (conservative voxelization): take
 * the medium voxel among the 26 neighbours of ijk whose centre is nearest
 * to v (voxel units), so that the point's own side of a wall wins. The
 * squared distance is a sum over the axes, and along each axis the offsets
 * 0, toward v's nearer side, away from it come in growing order: a branch
 * and bound in that order skips most neighbours after the first medium one
 * (~10% of a corridor's queries land here, next to an edge). */
static uint32_t neighbour_node(const SgImportanceCache *c, const double v[3], const int ijk[3])
{
    const int dims[3] = {c->header.nx, c->header.ny, c->header.nz};
    double term[3][3];
    int at[3][3];      /* the neighbour's index along the axis */
    bool inside[3][3]; /* ... within the grid */
    for (int a = 0; a < 3; a++) {
        double f = v[a] - ijk[a] - 0.5; /* in [-0.5, 0.5) */
        int s = f < 0.0 ? -1 : 1;
        const int o[3] = {0, s, -s};
        for (int k = 0; k < 3; k++) {
            double t = f - o[k];
            term[a][k] = t * t;
            at[a][k] = ijk[a] + o[k];
            inside[a][k] = (unsigned)at[a][k] < (unsigned)dims[a];
        }
    }
    double best = INFINITY;
    uint32_t n = SG_CACHE_NONE;
    for (int x = 0; x < 3 && term[0][x] < best; x++) {
        if (!inside[0][x])
            continue;
        for (int y = 0; y < 3 && term[0][x] + term[1][y] < best; y++) {
            if (!inside[1][y])
                continue;
            double dxy = term[0][x] + term[1][y];
            for (int z = 0; z < 3; z++) {
                double d2 = dxy + term[2][z];
                if (d2 >= best)
                    break;
                if (!inside[2][z] || (x == 0 && y == 0 && z == 0)) /* (0,0,0): the voxel itself, solid */
                    continue;
                uint32_t m = c->decoded
                                 ? c->decoded[grid_index(dims[0], dims[1], at[0][x], at[1][y], at[2][z])]
                                 : packed_voxel_node(c, at[0][x], at[1][y], at[2][z]);
                if (m & SG_CACHE_WALL_BIT)
                    m = SG_CACHE_NONE; /* a wall (marked or not) */
                if (m != SG_CACHE_NONE) {
                    best = d2;
                    n = m;
                    break; /* the rest of this row is farther */
                }
            }
        }
    }
    return n;
}

/* v in voxel units; NaN and far-out points fail the range test. */
static inline bool nearest_node_voxel(const SgImportanceCache *c, const double v[3], uint32_t *node)
{
    int ijk[3];
    if (!voxel_of(v, ijk))
        return false;
    uint32_t n;
    if (c->decoded && in_grid(c, ijk[0], ijk[1], ijk[2])) {
        unsigned octant = (v[0] >= ijk[0] + 0.5) | (v[1] >= ijk[1] + 0.5) << 1 | (v[2] >= ijk[2] + 0.5) << 2;
        uint32_t entry = c->decoded[grid_index(c->header.nx, c->header.ny, ijk[0], ijk[1], ijk[2])];
        n = sg_cache_entry_node(entry, c->octants, octant);
    } else {
        n = voxel_node(c, ijk[0], ijk[1], ijk[2]);
    }
    if (n == SG_CACHE_NONE)
        n = neighbour_node(c, v, ijk);
    if (n == SG_CACHE_NONE)
        return false;
    *node = n;
    return true;
}

bool sg_cache_nearest_node(const SgImportanceCache *c, const double p[3], uint32_t *node)
{
    double v[3];
    for (int a = 0; a < 3; a++)
        v[a] = (p[a] - c->header.origin[a]) * c->inv_voxel_size;
    return nearest_node_voxel(c, v, node);
}

bool sg_cache_nearest_node_voxel(const SgImportanceCache *c, const float v[3], uint32_t *node)
{
    double d[3] = {v[0], v[1], v[2]};
    return nearest_node_voxel(c, d, node);
}

/* The stored importance point of a node for a light (both in range). */
static inline void node_point(const SgImportanceCache *c, uint32_t node, uint32_t light, double point[3])
{
    const float *q = c->points + ((size_t)node * c->header.light_count + light) * 3;
    for (int a = 0; a < 3; a++)
        point[a] = q[a];
}

bool sg_cache_importance_point(const SgImportanceCache *c, const double p[3], uint32_t light,
                               double point[3])
{
    uint32_t n;
    if (light >= c->header.light_count || !sg_cache_nearest_node(c, p, &n))
        return false;
    uint32_t comp = c->lights[light].component;
    if (comp == SG_CACHE_NONE || (!c->one_component && c->nodes[n].component != comp))
        return false;
    node_point(c, n, light, point);
    return true;
}

bool sg_cache_light_reaches(const SgImportanceCache *c, uint32_t light, const double p[3])
{
    uint32_t n;
    if (light >= c->header.light_count || !sg_cache_nearest_node(c, p, &n))
        return false;
    uint32_t comp = c->lights[light].component;
    return comp != SG_CACHE_NONE && c->nodes[n].component == comp;
}

bool sg_cache_node_importance_point(const SgImportanceCache *c, uint32_t node, uint32_t light,
                                    double point[3])
{
    if (node >= c->header.node_count || light >= c->header.light_count)
        return false;
    uint32_t comp = c->lights[light].component;
    if (comp == SG_CACHE_NONE || c->nodes[node].component != comp)
        return false;
    node_point(c, node, light, point);
    return true;
}
