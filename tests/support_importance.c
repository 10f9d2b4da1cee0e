#include "support_importance.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "hash.h"
#include "importance_cache_format.h"

void sgt_medium_init(SgMedium *m, int nx, int ny, int nz)
{
    memset(m, 0, sizeof *m);
    double origin[3] = {0, 0, 0};
    SgError err = {0};
    if (!sg_grid_init(&m->grid, nx, ny, nz, origin, 1.0, &err))
        abort();
    m->geometry_hash = 0x1234abcd5678ef00ULL;
    m->resolution = nx > ny ? (nx > nz ? nx : nz) : (ny > nz ? ny : nz);
}

void sgt_box(SgMedium *m, int i0, int j0, int k0, int i1, int j1, int k1, uint8_t value)
{
    for (int k = k0; k <= k1; k++)
        for (int j = j0; j <= j1; j++)
            for (int i = i0; i <= i1; i++)
                if (sg_grid_inside(&m->grid, i, j, k))
                    m->grid.voxels[sg_grid_index(&m->grid, i, j, k)] = value;
}

uint32_t sgt_add_light(SgMedium *m, const double p[3], const int seed[3])
{
    m->lights = realloc(m->lights, (m->light_count + 1) * sizeof *m->lights);
    SgMediumLight *l = &m->lights[m->light_count];
    memset(l, 0, sizeof *l);
    memcpy(l->position, p, sizeof l->position);
    l->normal[1] = -1;
    l->power = 1;
    l->radiance[0] = l->radiance[1] = l->radiance[2] = 1;
    for (int a = 0; a < 3; a++)
        l->seed[a] = seed ? seed[a] : -1;
    return m->light_count++;
}

void sgt_medium_boxes(SgMedium *m, int nx, int ny, int nz, const int (*boxes)[7], int count)
{
    sgt_medium_init(m, nx, ny, nz);
    for (int b = 0; b < count; b++)
        sgt_box(m, boxes[b][0], boxes[b][1], boxes[b][2], boxes[b][3], boxes[b][4], boxes[b][5],
                (uint8_t)boxes[b][6]);
}

void sgt_medium_open(SgMedium *m, int nx, int ny, int nz)
{
    const int all[1][7] = {{0, 0, 0, nx - 1, ny - 1, nz - 1, 1}};
    sgt_medium_boxes(m, nx, ny, nz, all, 1);
}

void sgt_medium_free(SgMedium *m)
{
    sg_grid_release(&m->grid);
    free(m->lights);
    memset(m, 0, sizeof *m);
}

uint32_t sgt_node(SgSkeleton *s, int i, int j, int k, SgNodeKind kind, int light)
{
    s->nodes = realloc(s->nodes, (s->node_count + 1) * sizeof *s->nodes);
    SgSkeletonNode *n = &s->nodes[s->node_count];
    memset(n, 0, sizeof *n);
    n->voxel[0] = i;
    n->voxel[1] = j;
    n->voxel[2] = k;
    n->position[0] = (float)i + 0.5f;
    n->position[1] = (float)j + 0.5f;
    n->position[2] = (float)k + 0.5f;
    n->kind = (uint8_t)kind;
    n->light = kind == SG_NODE_LIGHT ? light : -1;
    n->radius = 1;
    return s->node_count++;
}

void sgt_edge(SgSkeleton *s, uint32_t a, uint32_t b)
{
    s->edges = realloc(s->edges, (s->edge_count + 1) * sizeof *s->edges);
    s->edges[s->edge_count][0] = a;
    s->edges[s->edge_count][1] = b;
    s->edge_count++;
}

uint32_t sgt_line(SgSkeleton *s, uint32_t from, const int a[3], const int b[3])
{
    int d[3], steps = 0;
    for (int x = 0; x < 3; x++) {
        d[x] = b[x] - a[x];
        int ad = abs(d[x]);
        if (ad > steps)
            steps = ad;
    }
    uint32_t last = from;
    for (int t = 0; t <= steps; t++) {
        int v[3];
        for (int x = 0; x < 3; x++)
            v[x] = a[x] + (steps ? (int)((double)d[x] * t / steps + (d[x] >= 0 ? 0.5 : -0.5)) : 0);
        if (last != SG_CACHE_NONE && s->nodes[last].voxel[0] == v[0] &&
            s->nodes[last].voxel[1] == v[1] && s->nodes[last].voxel[2] == v[2])
            continue;
        uint32_t n = sgt_node(s, v[0], v[1], v[2], SG_NODE_PLAIN, -1);
        if (last != SG_CACHE_NONE)
            sgt_edge(s, last, n);
        last = n;
    }
    return last;
}

void sgt_cache_fix_checksum(uint8_t *data, size_t size)
{
    SgCacheHeader h;
    if (size < sizeof h)
        return;
    memcpy(&h, data, sizeof h);
    h.checksum = 0;
    memcpy(data, &h, sizeof h);
    h.checksum = sg_hash_bytes(SG_HASH_INIT, data, size);
    memcpy(data, &h, sizeof h);
}

uint8_t *sgt_read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *data = aligned_alloc(16, ((size_t)n + 16) & ~(size_t)15);
    if (fread(data, 1, (size_t)n, f) != (size_t)n) {
        free(data);
        data = NULL;
    }
    fclose(f);
    *size = (size_t)n;
    return data;
}

void sgt_temp_path(char *out, size_t cap, const char *tag)
{
    snprintf(out, cap, "/tmp/sg_test_imp_%s_%ld", tag, (long)getpid());
}

/* Two rooms (x 1..13 and 17..28) with no opening between them; a light
 * with a skeleton line in each, and a third light sealed inside the wall
 * (no seed, no node). */
void sgt_sealed_rooms(SgMedium *medium, SgSkeleton *skeleton)
{
    SgMedium m;
    sgt_medium_init(&m, 30, 12, 5);
    sgt_box(&m, 1, 1, 1, 13, 10, 3, 1);
    sgt_box(&m, 17, 1, 1, 28, 10, 3, 1);
    double l0[3] = {14.0, 6.5, 2.5}, l1[3] = {29.0, 6.5, 2.5}, l2[3] = {15.0, 6.0, 2.0};
    int s0[3] = {13, 6, 2}, s1[3] = {28, 6, 2};
    sgt_add_light(&m, l0, s0);
    sgt_add_light(&m, l1, s1);
    sgt_add_light(&m, l2, NULL);
    SgSkeleton s = {0};
    int a0[3] = {2, 6, 2}, a1[3] = {13, 6, 2}, b0[3] = {17, 6, 2}, b1[3] = {28, 6, 2};
    uint32_t e0 = sgt_line(&s, SG_CACHE_NONE, a0, a1);
    uint32_t e1 = sgt_line(&s, SG_CACHE_NONE, b0, b1);
    s.nodes[e0].kind = SG_NODE_LIGHT;
    s.nodes[e0].light = 0;
    s.nodes[e1].kind = SG_NODE_LIGHT;
    s.nodes[e1].light = 1;
    *medium = m;
    *skeleton = s;
}
