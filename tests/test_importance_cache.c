/* importance.cache reader: a deterministic corruption sweep. Truncations at
 * every section boundary, byte flips in every section, and forged files
 * whose checksum is right but whose content is not (wrong magic, version,
 * offsets, indices) must all be refused with a message naming the file;
 * each candidate is given in an exact-size buffer so that ASan catches any
 * read out of bounds. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../importance/importance.h"
#include "importance_cache.h"
#include "importance_cache_format.h"
#include "support_importance.h"

static uint8_t *good;
static size_t good_size;

/* Two rooms and a door, two lights (one sealed): every section non-empty. */
static void build_good(void)
{
    SgMedium m;
    sgt_medium_init(&m, 44, 24, 5);
    sgt_box(&m, 1, 1, 1, 19, 22, 3, 1);
    sgt_box(&m, 22, 1, 1, 42, 22, 3, 1);
    sgt_box(&m, 20, 2, 1, 21, 4, 3, 1);
    double lp[3] = {43.0, 12.5, 2.5}, lq[3] = {0, 0, 0};
    int seed[3] = {42, 12, 2};
    sgt_add_light(&m, lp, seed);
    sgt_add_light(&m, lq, NULL);
    SgSkeleton s = {0};
    int p0[3] = {10, 12, 2}, p1[3] = {16, 3, 2}, p2[3] = {25, 3, 2}, p3[3] = {42, 12, 2};
    uint32_t n = sgt_line(&s, SG_CACHE_NONE, p0, p1);
    n = sgt_line(&s, n, p1, p2);
    n = sgt_line(&s, n, p2, p3);
    s.nodes[n].kind = SG_NODE_LIGHT;
    s.nodes[n].light = 0;
    char path[256];
    sgt_temp_path(path, sizeof path, "sweep");
    SgError err = {0};
    cr_assert(sg_importance_build(&m, &s, NULL, path, NULL, &err), "%s", err.message);
    good = sgt_read_file(path, &good_size);
    cr_assert_not_null(good);
    unlink(path);
    sg_skeleton_release(&s);
    sgt_medium_free(&m);
}

static void free_good(void) { free(good); }

static const SgCacheHeader *good_header(void) { return (const SgCacheHeader *)good; }

/* Opens a copy of bytes [0, size) of data; returns whether it was accepted. */
static bool accepted(const uint8_t *data, size_t size, char *message, size_t cap)
{
    uint8_t *copy = aligned_alloc(16, (size + 16) & ~(size_t)15);
    memcpy(copy, data, size);
    SgError err = {0};
    SgImportanceCache *c = sg_cache_open_memory(copy, size, "x.cache", &err);
    if (message)
        snprintf(message, cap, "%s", err.message);
    bool ok = c != NULL;
    if (c) {
        /* Accepted: every lookup must stay in bounds. */
        for (double x = -2; x < 46; x += 0.7)
            for (double y = -2; y < 26; y += 0.9) {
                double p[3] = {x, y, 2.2}, q[3];
                sg_cache_importance_point(c, p, 0, q);
                sg_cache_importance_point(c, p, 1, q);
            }
        sg_cache_close(c);
    }
    free(copy);
    return ok;
}

static void expect_refused(const uint8_t *data, size_t size, const char *what, const char *word)
{
    char message[1024];
    cr_assert_not(accepted(data, size, message, sizeof message), "accepted: %s", what);
    cr_assert(strncmp(message, "x.cache: ", 9) == 0, "%s: message '%s'", what, message);
    if (word)
        cr_assert(strstr(message, word) != NULL, "%s: message '%s' lacks '%s'", what, message,
                  word);
}

TestSuite(importance_cache_sweep, .init = build_good, .fini = free_good);

Test(importance_cache_sweep, the_reference_file_is_accepted)
{
    cr_assert(accepted(good, good_size, NULL, 0));
    for (int s = 0; s < SG_CACHE_SECTION_COUNT; s++)
        cr_assert_gt(good_header()->sections[s].size, 0, "section %d empty", s);
}

Test(importance_cache_sweep, truncation_at_every_section_boundary)
{
    const SgCacheHeader *h = good_header();
    size_t cuts[4 * SG_CACHE_SECTION_COUNT + 8];
    int n = 0;
    cuts[n++] = 0;
    cuts[n++] = 7;
    cuts[n++] = sizeof *h - 1;
    cuts[n++] = sizeof *h;
    cuts[n++] = good_size - 1;
    for (int s = 0; s < SG_CACHE_SECTION_COUNT; s++) {
        cuts[n++] = h->sections[s].offset;
        cuts[n++] = h->sections[s].offset + 1;
        cuts[n++] = h->sections[s].offset + h->sections[s].size / 2;
        cuts[n++] = h->sections[s].offset + h->sections[s].size - 1;
    }
    for (int i = 0; i < n; i++) {
        char what[64];
        snprintf(what, sizeof what, "cut at %zu", cuts[i]);
        expect_refused(good, cuts[i], what, "truncated");
    }
    /* And every 97th length in between. */
    for (size_t len = 0; len < good_size; len += 97)
        expect_refused(good, len, "cut", NULL);
}

Test(importance_cache_sweep, byte_flips_in_every_section_fail_the_checksum)
{
    const SgCacheHeader *h = good_header();
    uint8_t *bad = malloc(good_size);
    size_t spots[3 * SG_CACHE_SECTION_COUNT + 4];
    int n = 0;
    spots[n++] = 20; /* file size field */
    spots[n++] = offsetof(SgCacheHeader, geometry_hash);
    spots[n++] = offsetof(SgCacheHeader, sections) + 3;
    for (int s = 0; s < SG_CACHE_SECTION_COUNT; s++) {
        spots[n++] = h->sections[s].offset;
        spots[n++] = h->sections[s].offset + h->sections[s].size / 2;
        spots[n++] = h->sections[s].offset + h->sections[s].size - 1;
    }
    for (int i = 0; i < n; i++)
        for (int bit = 0; bit < 8; bit += 3) {
            memcpy(bad, good, good_size);
            bad[spots[i]] ^= (uint8_t)(1u << bit);
            char what[64];
            snprintf(what, sizeof what, "flip at %zu bit %d", spots[i], bit);
            expect_refused(bad, good_size, what, NULL);
        }
    free(bad);
}

/* Forgeries: change a field, fix the checksum, expect `word` in the error. */
typedef void (*Forge)(uint8_t *data, SgCacheHeader *h);

static void forged(Forge forge, const char *what, const char *word)
{
    uint8_t *bad = aligned_alloc(16, (good_size + 16) & ~(size_t)15);
    memcpy(bad, good, good_size);
    SgCacheHeader h;
    memcpy(&h, bad, sizeof h);
    forge(bad, &h);
    memcpy(bad, &h, sizeof h);
    sgt_cache_fix_checksum(bad, good_size);
    expect_refused(bad, good_size, what, word);
    free(bad);
}

static void f_magic(uint8_t *d, SgCacheHeader *h) { (void)d; h->magic[0] = 'X'; }
static void f_version(uint8_t *d, SgCacheHeader *h) { (void)d; h->version = 2; }
static void f_header_size(uint8_t *d, SgCacheHeader *h) { (void)d; h->header_size = 8; }
static void f_nodes_far(uint8_t *d, SgCacheHeader *h)
{
    (void)d;
    h->sections[SG_CACHE_NODES].offset = (uint64_t)1 << 40;
}
static void f_points_wrap(uint8_t *d, SgCacheHeader *h)
{
    (void)d;
    h->sections[SG_CACHE_POINTS].size = UINT64_MAX - 8;
}
static void f_misaligned(uint8_t *d, SgCacheHeader *h)
{
    (void)d;
    h->sections[SG_CACHE_PALETTE].offset += 4;
}
static void f_into_header(uint8_t *d, SgCacheHeader *h)
{
    (void)d;
    h->sections[SG_CACHE_BLOCKS].offset = 0;
}
static void f_node_count(uint8_t *d, SgCacheHeader *h) { (void)d; h->node_count += 1; }
static void f_light_count(uint8_t *d, SgCacheHeader *h) { (void)d; h->light_count = 0x40000000; }
static void f_grid(uint8_t *d, SgCacheHeader *h) { (void)d; h->nx = -3; }
static void f_voxel_size(uint8_t *d, SgCacheHeader *h) { (void)d; h->voxel_size = NAN; }
static void f_block_count(uint8_t *d, SgCacheHeader *h) { (void)d; h->block_count += 1; }
static void f_block_index(uint8_t *d, SgCacheHeader *h)
{
    uint32_t *index = (uint32_t *)(d + h->sections[SG_CACHE_BLOCK_INDEX].offset);
    size_t n = h->sections[SG_CACHE_BLOCK_INDEX].size / 4;
    for (size_t b = 0; b < n; b++)
        if (index[b] != SG_CACHE_NONE) {
            index[b] = h->block_count;
            return;
        }
}
static void f_block_bits(uint8_t *d, SgCacheHeader *h)
{
    SgCacheBlock *r = (SgCacheBlock *)(d + h->sections[SG_CACHE_BLOCKS].offset);
    r[0].bits = 3;
}
static void f_block_data(uint8_t *d, SgCacheHeader *h)
{
    SgCacheBlock *r = (SgCacheBlock *)(d + h->sections[SG_CACHE_BLOCKS].offset);
    uint32_t last = h->block_count - 1;
    r[last].data_offset = (uint32_t)h->sections[SG_CACHE_VOXEL_BITS].size;
    if (r[last].bits == 0)
        r[last].bits = 1, r[last].palette_size = 1;
}
static void f_block_palette(uint8_t *d, SgCacheHeader *h)
{
    SgCacheBlock *r = (SgCacheBlock *)(d + h->sections[SG_CACHE_BLOCKS].offset);
    r[0].palette_offset = (uint32_t)h->palette_count;
}
static void f_palette_node(uint8_t *d, SgCacheHeader *h)
{
    uint32_t *p = (uint32_t *)(d + h->sections[SG_CACHE_PALETTE].offset);
    for (uint64_t i = 0; i < h->palette_count; i++)
        if (p[i] != SG_CACHE_NONE) {
            p[i] = h->node_count;
            return;
        }
}
static void f_node_component(uint8_t *d, SgCacheHeader *h)
{
    SgCacheNode *n = (SgCacheNode *)(d + h->sections[SG_CACHE_NODES].offset);
    n[2].component = h->component_count;
}
static void f_light_node(uint8_t *d, SgCacheHeader *h)
{
    SgCacheLight *l = (SgCacheLight *)(d + h->sections[SG_CACHE_LIGHTS].offset);
    l[0].node = h->node_count + 7;
}
static void f_point_nan(uint8_t *d, SgCacheHeader *h)
{
    float *p = (float *)(d + h->sections[SG_CACHE_POINTS].offset);
    p[4] = NAN;
}

Test(importance_cache_sweep, forged_files_with_a_valid_checksum)
{
    forged(f_magic, "magic", "magic");
    forged(f_version, "version", "version 2");
    forged(f_header_size, "header size", "header size");
    forged(f_nodes_far, "nodes offset far away", "out of range");
    forged(f_points_wrap, "points size wraps", "out of range");
    forged(f_misaligned, "misaligned palette", "out of range");
    forged(f_into_header, "blocks over the header", "out of range");
    forged(f_node_count, "node count", "section");
    forged(f_light_count, "light count", "section");
    forged(f_grid, "negative grid", "grid");
    forged(f_voxel_size, "NaN voxel size", "transform");
    forged(f_block_count, "block count", "section");
    forged(f_block_index, "block index", "block index");
    forged(f_block_bits, "block bits", "block record");
    forged(f_block_data, "block data", "block record");
    forged(f_block_palette, "block palette", "block record");
    forged(f_palette_node, "palette node", "palette");
    forged(f_node_component, "node component", "node 2");
    forged(f_light_node, "light node", "light 0");
    forged(f_point_nan, "NaN point", "importance point 1");
}

Test(importance_cache_sweep, files_on_disk_missing_foreign_truncated)
{
    char path[256];
    sgt_temp_path(path, sizeof path, "disk");
    SgError err = {0};
    cr_assert_null(sg_cache_open("/nonexistent/importance.cache", &err));
    cr_assert(strstr(err.message, "/nonexistent/importance.cache: ") == err.message, "%s",
              err.message);
    /* Foreign: a PLY file. */
    FILE *f = fopen(path, "wb");
    const char *ply = "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
    for (int i = 0; i < 20; i++)
        fputs(ply, f);
    fclose(f);
    err = (SgError){0};
    cr_assert_null(sg_cache_open(path, &err));
    cr_assert(strstr(err.message, path) == err.message && strstr(err.message, "magic"), "%s",
              err.message);
    /* Truncated in the middle of the voxel bits. */
    f = fopen(path, "wb");
    fwrite(good, 1, good_size - 40, f);
    fclose(f);
    err = (SgError){0};
    cr_assert_null(sg_cache_open(path, &err));
    cr_assert(strstr(err.message, "truncated") != NULL, "%s", err.message);
    /* Empty. */
    f = fopen(path, "wb");
    fclose(f);
    err = (SgError){0};
    cr_assert_null(sg_cache_open(path, &err));
    cr_assert(strstr(err.message, "truncated") != NULL, "%s", err.message);
    /* The intact file opens. */
    f = fopen(path, "wb");
    fwrite(good, 1, good_size, f);
    fclose(f);
    err = (SgError){0};
    SgImportanceCache *c = sg_cache_open(path, &err);
    cr_assert_not_null(c, "%s", err.message);
    cr_assert_eq(sg_cache_bytes(c), good_size);
    sg_cache_close(c);
    unlink(path);
}
