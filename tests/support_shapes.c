#include "support_shapes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"

typedef struct ShapeDef {
    SgShapeInfo info;
    int size[3];
    int light_count;
    double lights[2][3];
} ShapeDef;

static const ShapeDef shapes[SG_SHAPE_COUNT] = {
    [SG_SHAPE_BAR] = {{"bar", 1, 0, 0}, {4, 4, 24}, 1, {{2, 2, 1}}},
    [SG_SHAPE_CUBE] = {{"cube", 1, 0, 0}, {12, 12, 12}, 1, {{6, 11.5, 6}}},
    [SG_SHAPE_TORUS] = {{"torus", 1, 1, 0}, {28, 28, 10}, 1, {{23, 14, 5}}},
    [SG_SHAPE_PILLAR_ROOM] = {{"pillar room", 1, 1, 0}, {24, 16, 20}, 1, {{4, 15.5, 4}}},
    [SG_SHAPE_THREE_PILLARS] = {{"three-pillar room", 1, 3, 0}, {36, 16, 20}, 1, {{4, 15.5, 4}}},
    [SG_SHAPE_RING] = {{"ring corridor", 1, 1, 0}, {24, 8, 24}, 1, {{6, 4, 6}}},
    [SG_SHAPE_LAMP_ROOM] = {{"floating-lamp room", 1, 0, 1}, {24, 16, 20}, 1, {{12, 15.5, 10}}},
    [SG_SHAPE_U] = {{"U corridor", 1, 0, 0}, {24, 8, 20}, 1, {{5, 4, 17}}},
    [SG_SHAPE_SHELL] = {{"hollow sphere", 1, 0, 1}, {24, 24, 24}, 1, {{12, 12, 20}}},
    [SG_SHAPE_TWO_ROOMS] = {{"two rooms", 2, 0, 0}, {30, 10, 12}, 2, {{7, 5, 6}, {23, 5, 6}}},
    [SG_SHAPE_RING_LAMP] = {{"floating-ring room", 1, 1, 1}, {32, 20, 32}, 1, {{16, 19.5, 16}}},
};

const SgShapeInfo *sg_shape_info(SgShape shape)
{
    return shape < SG_SHAPE_COUNT ? &shapes[shape].info : NULL;
}

static bool in_box(double x, double y, double z, double x0, double x1, double y0, double y1,
                   double z0, double z1)
{
    return x >= x0 && x < x1 && y >= y0 && y < y1 && z >= z0 && z < z1;
}

/* Is the point (description units) air? */
static bool is_air(SgShape shape, double x, double y, double z)
{
    switch (shape) {
    case SG_SHAPE_BAR:
    case SG_SHAPE_CUBE:
        return true;
    case SG_SHAPE_TORUS: {
        double r = hypot(x - 14, y - 14) - 9;
        return r * r + (z - 5) * (z - 5) < 16;
    }
    case SG_SHAPE_PILLAR_ROOM:
        return !in_box(x, y, z, 10, 14, 0, 16, 8, 12);
    case SG_SHAPE_THREE_PILLARS:
        return !in_box(x, y, z, 6, 10, 0, 16, 8, 12) && !in_box(x, y, z, 16, 20, 0, 16, 8, 12) &&
               !in_box(x, y, z, 26, 30, 0, 16, 8, 12);
    case SG_SHAPE_RING:
        return in_box(x, y, z, 3, 21, 2, 6, 3, 21) && !in_box(x, y, z, 9, 15, 0, 8, 9, 15);
    case SG_SHAPE_LAMP_ROOM:
        return !in_box(x, y, z, 9, 15, 9, 12, 7, 13);
    case SG_SHAPE_U:
        return in_box(x, y, z, 2, 8, 2, 6, 2, 18) || in_box(x, y, z, 16, 22, 2, 6, 2, 18) ||
               in_box(x, y, z, 2, 22, 2, 6, 2, 8);
    case SG_SHAPE_SHELL: {
        double r = sqrt((x - 12) * (x - 12) + (y - 12) * (y - 12) + (z - 12) * (z - 12));
        return r > 6 && r < 10;
    }
    case SG_SHAPE_TWO_ROOMS:
        return in_box(x, y, z, 1, 13, 1, 9, 1, 11) || in_box(x, y, z, 17, 29, 1, 9, 1, 11);
    case SG_SHAPE_RING_LAMP: {
        double r = hypot(x - 16, z - 16) - 8;
        return r * r + (y - 10) * (y - 10) >= 2.5 * 2.5;
    }
    default:
        return false;
    }
}

static bool medium_alloc(SgMedium *m, int nx, int ny, int nz, double voxel, int lights)
{
    memset(m, 0, sizeof *m);
    double origin[3] = {0, 0, 0};
    SgError err = {0};
    if (!sg_grid_init(&m->grid, nx, ny, nz, origin, voxel, &err))
        return false;
    m->lights = calloc((size_t)(lights ? lights : 1), sizeof *m->lights);
    if (!m->lights) {
        sg_grid_release(&m->grid);
        return false;
    }
    m->light_count = (uint32_t)lights;
    return true;
}

static void set_light(SgMedium *m, int i, const double p[3])
{
    SgMediumLight *l = &m->lights[i];
    memcpy(l->position, p, sizeof l->position);
    l->normal[1] = -1;
    l->power = 1;
    l->radiance[0] = l->radiance[1] = l->radiance[2] = 1;
    sg_grid_world_to_voxel(&m->grid, p, l->seed);
}

bool sg_shape_medium(SgShape shape, int scale, SgMedium *m)
{
    if (shape >= SG_SHAPE_COUNT || scale < 1)
        return false;
    const ShapeDef *d = &shapes[shape];
    if (!medium_alloc(m, d->size[0] * scale, d->size[1] * scale, d->size[2] * scale, 1.0 / scale,
                      d->light_count))
        return false;
    SgGrid *g = &m->grid;
    for (int k = 0; k < g->nz; k++)
        for (int j = 0; j < g->ny; j++)
            for (int i = 0; i < g->nx; i++)
                g->voxels[sg_grid_index(g, i, j, k)] =
                    is_air(shape, (i + 0.5) / scale, (j + 0.5) / scale, (k + 0.5) / scale);
    for (int i = 0; i < d->light_count; i++)
        set_light(m, i, d->lights[i]);
    m->resolution = g->nx > g->ny ? (g->nx > g->nz ? g->nx : g->nz) : (g->ny > g->nz ? g->ny : g->nz);
    return true;
}

void sg_shape_roughen(SgMedium *m, double p, uint64_t seed)
{
    SgGrid *g = &m->grid;
    SgRng rng;
    sg_rng_seed(&rng, seed, 7);
    size_t n = sg_grid_count(g);
    uint8_t *next = malloc(n);
    if (!next)
        return;
    memcpy(next, g->voxels, n);
    for (size_t v = 0; v < n; v++) {
        if (!g->voxels[v])
            continue;
        int c[3];
        sg_grid_coords(g, v, c);
        int i = c[0], j = c[1], k = c[2];
        bool wall = !sg_grid_get(g, i - 1, j, k) || !sg_grid_get(g, i + 1, j, k) ||
                    !sg_grid_get(g, i, j - 1, k) || !sg_grid_get(g, i, j + 1, k) ||
                    !sg_grid_get(g, i, j, k - 1) || !sg_grid_get(g, i, j, k + 1);
        float u = sg_rng_float(&rng);
        if (wall && u < p)
            next[v] = 0;
    }
    for (uint32_t l = 0; l < m->light_count; l++) {
        const int *s = m->lights[l].seed;
        if (sg_grid_inside(g, s[0], s[1], s[2]))
            next[sg_grid_index(g, s[0], s[1], s[2])] = 1;
    }
    memcpy(g->voxels, next, n);
    free(next);
}

bool sg_shape_furnished_room(int nx, int ny, int nz, SgMedium *m)
{
    if (!medium_alloc(m, nx, ny, nz, 1.0, 1))
        return false;
    SgGrid *g = &m->grid;
    /* proportions of a room: y is up */
    double X = nx, Y = ny, Z = nz;
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++) {
                double x = i + 0.5, y = j + 0.5, z = k + 0.5;
                bool solid = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
                /* pillar, floor to ceiling */
                solid |= in_box(x, y, z, 0.62 * X, 0.70 * X, 0, Y, 0.45 * Z, 0.51 * Z);
                /* table: top and four legs */
                solid |= in_box(x, y, z, 0.15 * X, 0.50 * X, 0.35 * Y, 0.38 * Y, 0.15 * Z, 0.35 * Z);
                for (int leg = 0; leg < 4; leg++) {
                    double lx = leg & 1 ? 0.46 * X : 0.16 * X, lz = leg & 2 ? 0.31 * Z : 0.16 * Z;
                    solid |= in_box(x, y, z, lx, lx + 0.03 * X, 0, 0.35 * Y, lz, lz + 0.03 * Z);
                }
                /* sofa: seat and back against the far wall */
                solid |= in_box(x, y, z, 0.10 * X, 0.60 * X, 0, 0.22 * Y, 0.80 * Z, 0.95 * Z);
                solid |= in_box(x, y, z, 0.10 * X, 0.60 * X, 0, 0.45 * Y, 0.92 * Z, 0.99 * Z);
                /* lamp shade on a cord from the ceiling */
                solid |= in_box(x, y, z, 0.40 * X, 0.42 * X, 0.75 * Y, Y, 0.60 * Z, 0.62 * Z);
                solid |= in_box(x, y, z, 0.33 * X, 0.49 * X, 0.70 * Y, 0.75 * Y, 0.53 * Z, 0.69 * Z);
                g->voxels[sg_grid_index(g, i, j, k)] = !solid;
            }
    double light[3] = {0.8 * X, Y - 1.5, 0.2 * Z};
    set_light(m, 0, light);
    m->resolution = nx > ny ? (nx > nz ? nx : nz) : (ny > nz ? ny : nz);
    return true;
}

void sg_shape_medium_free(SgMedium *m)
{
    sg_grid_release(&m->grid);
    free(m->lights);
    memset(m, 0, sizeof *m);
}
