#include "voxelize.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "progress.h"
#include "row_runs.h"
#include "threads.h"
#include "union_find.h"
#include "vecmath.h"

/* Slack of the overlap test, in voxels. Geometry that lies exactly on a
 * voxel face touches it in every unit; rounding of (p - origin) / h may put
 * it 1e-16 off in one unit and not in another. With the slack both count as
 * touching, so the grid does not depend on the scene's unit. */
#define TOUCH_SLACK 1e-7

/* ---- triangle / box overlap (separating axis theorem) ------------------- */

static bool separated_on_axis(const double axis[3], const double v0[3], const double v1[3],
                              const double v2[3], double half)
{
    double p0 = d3_dot(axis, v0), p1 = d3_dot(axis, v1), p2 = d3_dot(axis, v2);
    double lo = fmin(p0, fmin(p1, p2)), hi = fmax(p0, fmax(p1, p2));
    double r = half * (fabs(axis[0]) + fabs(axis[1]) + fabs(axis[2]));
    return lo > r || hi < -r;
}

bool sg_triangle_box_overlap(const double centre[3], double half, const double a[3],
                             const double b[3], const double c[3])
{
    double v0[3], v1[3], v2[3];
    d3_sub(a, centre, v0);
    d3_sub(b, centre, v1);
    d3_sub(c, centre, v2);
    /* The box's own axes: bounding boxes must overlap. */
    for (int k = 0; k < 3; k++) {
        double lo = fmin(v0[k], fmin(v1[k], v2[k])), hi = fmax(v0[k], fmax(v1[k], v2[k]));
        if (lo > half || hi < -half)
            return false;
    }
    double e[3][3];
    d3_sub(v1, v0, e[0]);
    d3_sub(v2, v1, e[1]);
    d3_sub(v0, v2, e[2]);
    /* The triangle's plane. */
    double n[3];
    d3_cross(e[0], e[1], n);
    if (separated_on_axis(n, v0, v1, v2, half))
        return false;
    /* Cross products of box axes and triangle edges. */
    for (int k = 0; k < 3; k++) {
        double unit[3] = {0, 0, 0};
        unit[k] = 1;
        for (int i = 0; i < 3; i++) {
            double axis[3];
            d3_cross(unit, e[i], axis);
            if (separated_on_axis(axis, v0, v1, v2, half))
                return false;
        }
    }
    return true;
}

/* ---- grid placement ----------------------------------------------------- */

/* Light from outside: a margin of air round the bounds, where the sky is,
 * reached through the scene's openings; 0 for a closed scene. */
static int outside_margin(const SgScene *scene)
{
    return sg_scene_lit_from_outside(scene) ? SG_VOXELIZE_OUTSIDE_MARGIN : 0;
}

bool sg_voxelize_grid_for(const SgScene *scene, int resolution, SgGrid *grid, SgError *err)
{
    if (resolution < 1 || resolution > SG_VOXEL_RESOLUTION_MAX)
        return sg_fail(err, "%s: resolution %d is outside [1, %d]", scene->path, resolution,
                       SG_VOXEL_RESOLUTION_MAX);
    double extent[3], longest = 0;
    for (int a = 0; a < 3; a++) {
        extent[a] = scene->bounds_max[a] - scene->bounds_min[a];
        longest = fmax(longest, extent[a]);
    }
    if (!(longest > 0) || !isfinite(longest))
        return sg_fail(err, "%s: the scene's bounding box is empty or not finite", scene->path);
    double h = longest / resolution;
    int dims[3];
    int margin = outside_margin(scene);
    double origin[3];
    for (int a = 0; a < 3; a++) {
        /* Relative slack so that 10.0 / 0.1 counts as 100 voxels, not 101. */
        double n = ceil(extent[a] / h - 1e-9);
        dims[a] = (n < 1 ? 1 : (int)n) + 2 * margin;
        origin[a] = scene->bounds_min[a] - margin * h;
    }
    SgError why = {0};
    if (!sg_grid_init(grid, dims[0], dims[1], dims[2], origin, h, &why))
        return sg_fail(err, "%s: resolution %d: %s", scene->path, resolution, why.message);
    return true;
}

/* ---- surface voxelization ----------------------------------------------- */

typedef struct SurfaceJob {
    const SgScene *scene;
    SgGrid *grid;
    uint32_t chunk;
} SurfaceJob;

static inline void mark_solid(SgGrid *g, int i, int j, int k)
{
    /* Threads may mark the same voxel: relaxed atomic stores of the same
     * value make that well defined and cost nothing on x86. */
    __atomic_store_n(&g->voxels[sg_grid_index(g, i, j, k)], (uint8_t)1, __ATOMIC_RELAXED);
}

static int clampi(int v, int lo, int hi) { return v < lo ? lo : v > hi ? hi : v; }

/* Voxelizes one triangle, in voxel units (q = (p - origin) / h). Walks the
 * columns along the normal's dominant axis and tests only the few voxels
 * per column that the plane crosses, so a large slanted triangle costs its
 * area, not its bounding box. */
static void voxelize_triangle(SgGrid *g, const double q[3][3])
{
    const double half = 0.5 + TOUCH_SLACK;
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        double mn = fmin(q[0][a], fmin(q[1][a], q[2][a]));
        double mx = fmax(q[0][a], fmax(q[1][a], q[2][a]));
        double dim = a == 0 ? g->nx : a == 1 ? g->ny : g->nz;
        lo[a] = (int)floor(fmax(mn - TOUCH_SLACK, -1.0));
        hi[a] = (int)floor(fmin(mx + TOUCH_SLACK, dim));
        lo[a] = clampi(lo[a], 0, (int)dim - 1);
        hi[a] = clampi(hi[a], 0, (int)dim - 1);
        if (mx + TOUCH_SLACK < 0 || mn - TOUCH_SLACK > dim)
            return;
    }
    double e1[3], e2[3], n[3];
    d3_sub(q[1], q[0], e1);
    d3_sub(q[2], q[0], e2);
    d3_cross(e1, e2, n);
    int d = 0;
    for (int a = 1; a < 3; a++)
        if (fabs(n[a]) > fabs(n[d]))
            d = a;
    int u = (d + 1) % 3, v = (d + 2) % 3;
    double plane_c = d3_dot(n, q[0]);
    int ijk[3];
    for (int cu = lo[u]; cu <= hi[u]; cu++) {
        for (int cv = lo[v]; cv <= hi[v]; cv++) {
            int dlo = lo[d], dhi = hi[d];
            if (n[d] != 0) {
                /* The plane's d-coordinate over the column's square: its
                 * extremes are at the corners. */
                double mn = INFINITY, mx = -INFINITY;
                for (int corner = 0; corner < 4; corner++) {
                    double pu = cu + (corner & 1), pv = cv + (corner >> 1);
                    double pd = (plane_c - n[u] * pu - n[v] * pv) / n[d];
                    mn = fmin(mn, pd);
                    mx = fmax(mx, pd);
                }
                dlo = clampi((int)floor(fmax(mn - TOUCH_SLACK, lo[d] - 1.0)), lo[d], hi[d]);
                dhi = clampi((int)floor(fmin(mx + TOUCH_SLACK, hi[d] + 1.0)), lo[d], hi[d]);
            }
            for (int cd = dlo; cd <= dhi; cd++) {
                ijk[u] = cu;
                ijk[v] = cv;
                ijk[d] = cd;
                double centre[3] = {ijk[0] + 0.5, ijk[1] + 0.5, ijk[2] + 0.5};
                if (sg_triangle_box_overlap(centre, half, q[0], q[1], q[2]))
                    mark_solid(g, ijk[0], ijk[1], ijk[2]);
            }
        }
    }
}

#define TRIANGLES_PER_TASK 4096u

static void surface_task(void *ctx, uint64_t task, int thread)
{
    (void)thread;
    SurfaceJob *job = ctx;
    const SgScene *s = job->scene;
    SgGrid *g = job->grid;
    uint64_t first = task * TRIANGLES_PER_TASK;
    uint64_t last = first + TRIANGLES_PER_TASK;
    if (last > s->triangle_count)
        last = s->triangle_count;
    for (uint64_t t = first; t < last; t++) {
        /* Light passes through glass: it does not bound the medium. */
        if (s->materials[s->triangle_material[t]].type == SG_MATERIAL_DIELECTRIC)
            continue;
        double q[3][3];
        for (int c = 0; c < 3; c++) {
            const double *p = s->positions + 3 * (size_t)s->indices[3 * t + c];
            for (int a = 0; a < 3; a++)
                q[c][a] = (p[a] - g->origin[a]) / g->voxel_size;
        }
        voxelize_triangle(g, q);
    }
}

void sg_voxelize_surface(const SgScene *scene, SgGrid *grid, int threads)
{
    SurfaceJob job = {scene, grid, TRIANGLES_PER_TASK};
    uint64_t tasks = (scene->triangle_count + TRIANGLES_PER_TASK - 1) / TRIANGLES_PER_TASK;
    sg_parallel_for(tasks, threads, surface_task, &job);
}

/* ---- air components by runs --------------------------------------------- */

/* The air of each row (fixed j, k) as maximal runs of x; runs of
 * neighbouring rows that touch, even diagonally, are 26-connected. */
static bool build_runs(const SgGrid *g, SgRowRuns *r, SgError *err)
{
    size_t rows = (size_t)g->ny * g->nz;
    if (!sg_row_runs_begin(r, rows))
        return sg_fail(err, "out of memory for the air's runs");
    for (size_t row = 0; row < rows; row++) {
        sg_row_runs_start_row(r, row);
        const uint8_t *v = g->voxels + row * (size_t)g->nx;
        int i = 0;
        while (i < g->nx) {
            while (i < g->nx && v[i])
                i++;
            if (i >= g->nx)
                break;
            int i0 = i;
            while (i < g->nx && !v[i])
                i++;
            if (!sg_row_runs_push(r, (uint32_t)i0, (uint32_t)(i - 1)))
                return sg_fail(err, "out of memory for the air's runs");
        }
    }
    if (!sg_row_runs_end(r))
        return sg_fail(err, "out of memory for the air's runs");
    for (int k = 0; k < g->nz; k++)
        for (int j = 0; j < g->ny; j++) {
            uint32_t row = (uint32_t)(j + g->ny * k);
            /* Half of the 8 neighbouring rows; the rest see this one. */
            if (j > 0)
                sg_row_runs_connect(r, row, row - 1, 1, NULL, NULL);
            if (k > 0) {
                uint32_t below = row - (uint32_t)g->ny;
                sg_row_runs_connect(r, row, below, 1, NULL, NULL);
                if (j > 0)
                    sg_row_runs_connect(r, row, below - 1, 1, NULL, NULL);
                if (j + 1 < g->ny)
                    sg_row_runs_connect(r, row, below + 1, 1, NULL, NULL);
            }
        }
    return true;
}

/* The run holding air voxel (i,j,k), or UINT32_MAX. */
static uint32_t run_of(const SgGrid *g, const SgRowRuns *r, int i, int j, int k)
{
    uint32_t run = sg_row_runs_at(r, (size_t)j + (size_t)g->ny * k, (uint32_t)i);
    return run != UINT32_MAX && (uint32_t)i <= r->run[run].end ? run : UINT32_MAX;
}

/* ---- lights ------------------------------------------------------------- */

static bool is_air(const SgGrid *solid, int i, int j, int k)
{
    return sg_grid_inside(solid, i, j, k) && !solid->voxels[sg_grid_index(solid, i, j, k)];
}

/* The air voxel in front of an emitter at point p facing n: march along the
 * normal first (the light shines there), then the nearest air voxel around
 * p (closed emitters, zero normals). False if none within a few voxels. */
static bool find_seed(const SgGrid *solid, const double p[3], const double n[3], int seed[3])
{
    double h = solid->voxel_size;
    if (d3_length(n) > 0.5) {
        for (double t = 0.25; t <= 4.0; t += 0.25) {
            double q[3] = {p[0] + t * h * n[0], p[1] + t * h * n[1], p[2] + t * h * n[2]};
            int v[3];
            sg_grid_world_to_voxel(solid, q, v);
            if (is_air(solid, v[0], v[1], v[2])) {
                memcpy(seed, v, sizeof v);
                return true;
            }
        }
    }
    int c[3];
    sg_grid_world_to_voxel(solid, p, c);
    for (int radius = 1; radius <= 3; radius++) {
        double best = INFINITY;
        for (int dk = -radius; dk <= radius; dk++)
            for (int dj = -radius; dj <= radius; dj++)
                for (int di = -radius; di <= radius; di++) {
                    int i = c[0] + di, j = c[1] + dj, k = c[2] + dk;
                    if (!is_air(solid, i, j, k))
                        continue;
                    double centre[3], d[3];
                    sg_grid_voxel_center(solid, i, j, k, centre);
                    d3_sub(centre, p, d);
                    /* Prefer the side the emitter faces. */
                    double score = d3_dot(d, d) - 1e-3 * h * d3_dot(d, n);
                    if (score < best) {
                        best = score;
                        seed[0] = i;
                        seed[1] = j;
                        seed[2] = k;
                    }
                }
        if (best < INFINITY)
            return true;
    }
    return false;
}

/* ---- the whole step ----------------------------------------------------- */

/* The medium's light table: each guide light's position, power and the
 * air voxel it seeds (-1: sealed, so far). */
static bool medium_lights(const SgScene *scene, uint32_t light_count, SgMedium *medium, SgError *err)
{
    const SgGrid *g = &medium->grid;
    medium->lights = calloc(light_count, sizeof *medium->lights);
    if (!medium->lights)
        return sg_fail(err, "%s: out of memory", scene->path);
    medium->light_count = light_count;
    medium->outside_margin = outside_margin(scene);
    for (uint32_t k = 0; k < light_count; k++) {
        SgGuideLight l = sg_scene_guide_light(scene, k);
        SgMediumLight *ml = &medium->lights[k];
        memcpy(ml->position, l.position, sizeof ml->position);
        memcpy(ml->normal, l.normal, sizeof ml->normal);
        if (l.kind == SG_GUIDE_LIGHT_AREA)
            memcpy(ml->radiance, scene->lights[l.index].radiance, sizeof ml->radiance);
        else if (l.kind == SG_GUIDE_LIGHT_POINT)
            memcpy(ml->radiance, scene->light_sources[l.index].rgb, sizeof ml->radiance);
        ml->power = l.power;
        if (l.kind == SG_GUIDE_LIGHT_OUTSIDE || l.kind == SG_GUIDE_LIGHT_SUN) {
            /* a corner of the margin: air, joined to all the outside */
            ml->outside = l.kind == SG_GUIDE_LIGHT_OUTSIDE;
            ml->sun = l.kind == SG_GUIDE_LIGHT_SUN;
            if (ml->sun)
                memcpy(ml->radiance, scene->light_sources[l.index].rgb, sizeof ml->radiance);
            ml->seed[0] = ml->seed[1] = ml->seed[2] = 0;
            sg_grid_voxel_center(g, 0, 0, 0, ml->position);
        } else if (!find_seed(g, l.position, l.normal, ml->seed)) {
            ml->seed[0] = ml->seed[1] = ml->seed[2] = -1;
        }
    }
    return true;
}

/* Marks the component of the air voxel at seed as kept. */
static void keep_component_at(const SgGrid *g, const SgRowRuns *runs, const int seed[3], uint8_t *keep)
{
    uint32_t run = run_of(g, runs, seed[0], seed[1], seed[2]);
    if (run != UINT32_MAX)
        keep[sg_set_find(runs->parent, run)] = 1;
}

/* Keeps the air in front of each triangle of area light k (a long emitter
 * may face two rooms); returns whether the light is still sealed. */
static bool keep_in_front_of_triangles(const SgScene *scene, const SgGrid *g, const SgRowRuns *runs,
                                       uint32_t k, bool sealed, SgMediumLight *ml, uint8_t *keep)
{
    const SgLight *l = &scene->lights[k];
    for (uint32_t t = 0; t < l->triangle_count; t++) {
        uint32_t tri = scene->light_triangles[l->first_triangle + t];
        double n[3], c[3] = {0, 0, 0};
        sg_scene_triangle_normal(scene, tri, n);
        double len = d3_length(n);
        for (int a = 0; a < 3; a++) {
            n[a] /= len;
            for (int v = 0; v < 3; v++)
                c[a] += scene->positions[3 * (size_t)scene->indices[3 * (size_t)tri + v] + a] / 3;
        }
        int seed[3];
        if (find_seed(g, c, n, seed)) {
            keep_component_at(g, runs, seed, keep);
            if (sealed) {
                /* The centroid had no air in front (a ring-shaped lamp):
                 * any triangle's seed stands for the light. */
                memcpy(ml->seed, seed, sizeof seed);
                sealed = false;
            }
        }
    }
    return sealed;
}

/* Keep the components of every seed: the light's own, and the air in
 * front of each of its triangles. */
static void keep_lit_components(const SgScene *scene, const SgRowRuns *runs, SgMedium *medium, uint8_t *keep,
                                SgVoxelizeStats *stats)
{
    const SgGrid *g = &medium->grid;
    for (uint32_t k = 0; k < medium->light_count; k++) {
        SgMediumLight *ml = &medium->lights[k];
        bool sealed = ml->seed[0] < 0;
        if (!sealed)
            keep_component_at(g, runs, ml->seed, keep);
        if (k < scene->light_count) /* else a point light or the outside: its seed is all */
            sealed = keep_in_front_of_triangles(scene, g, runs, k, sealed, ml, keep);
        stats->sealed_lights += sealed;
    }
    for (uint32_t r = 0; r < runs->count; r++)
        if (runs->parent[r] == r) {
            stats->air_components++;
            stats->medium_components += keep[r];
        }
}

/* Camera state, judged on the solid grid before it is overwritten. */
static void camera_state(const SgScene *scene, const SgGrid *g, const SgRowRuns *runs, const uint8_t *keep,
                         SgVoxelizeStats *stats)
{
    if (!scene->has_camera)
        return;
    int c[3];
    sg_grid_world_to_voxel(g, scene->camera.position, c);
    stats->camera_in_grid = sg_grid_inside(g, c[0], c[1], c[2]);
    if (!stats->camera_in_grid)
        return;
    if (g->voxels[sg_grid_index(g, c[0], c[1], c[2])])
        stats->camera_voxel_state = 1;
    else {
        uint32_t run = run_of(g, runs, c[0], c[1], c[2]);
        stats->camera_voxel_state = keep[sg_set_find(runs->parent, run)] ? 2 : 0;
    }
}

/* The grid becomes the medium: 1 on kept runs, 0 elsewhere. */
static void fill_medium(SgGrid *g, const SgRowRuns *runs, const uint8_t *keep, SgVoxelizeStats *stats)
{
    memset(g->voxels, 0, sg_grid_count(g));
    size_t rows = (size_t)g->ny * g->nz;
    for (size_t row = 0; row < rows; row++) {
        uint8_t *v = g->voxels + row * (size_t)g->nx;
        for (uint32_t r = runs->row_first[row]; r < runs->row_first[row + 1]; r++)
            if (keep[sg_set_find(runs->parent, r)]) {
                uint32_t length = runs->run[r].end - runs->run[r].start + 1;
                memset(v + runs->run[r].start, 1, length);
                stats->medium_voxels += length;
            }
    }
}

/* The air connected to the lights, found on the runs of air voxels. */
static bool keep_lit_air(const SgScene *scene, SgMedium *medium, SgVoxelizeStats *stats, SgError *err)
{
    SgGrid *g = &medium->grid;
    SgRowRuns runs;
    if (!build_runs(g, &runs, err)) {
        sg_row_runs_release(&runs);
        return false;
    }
    uint8_t *keep = calloc(runs.count ? runs.count : 1, 1);
    if (!keep) {
        sg_row_runs_release(&runs);
        return sg_fail(err, "%s: out of memory", scene->path);
    }
    keep_lit_components(scene, &runs, medium, keep, stats);
    camera_state(scene, g, &runs, keep, stats);
    fill_medium(g, &runs, keep, stats);
    free(keep);
    sg_row_runs_release(&runs);
    return true;
}

bool sg_voxelize(const SgScene *scene, const SgVoxelizeOptions *options, SgMedium *medium,
                 SgVoxelizeStats *stats, SgError *err)
{
    SgVoxelizeStats ignored;
    if (!stats)
        stats = &ignored;
    SgVoxelizeOptions defaults = {0};
    if (!options)
        options = &defaults;
    memset(medium, 0, sizeof *medium);
    memset(stats, 0, sizeof *stats);
    uint32_t light_count = sg_scene_guide_light_count(scene);
    if (light_count == 0)
        return sg_fail(err, "%s: no light: give a material an emission (MTL Ke) or add \"lights\"",
                       scene->path);
    int resolution = options->resolution > 0          ? options->resolution
                     : scene->voxel_resolution > 0 ? scene->voxel_resolution
                                                   : SG_VOXELIZE_DEFAULT_RESOLUTION;
    SgGrid *g = &medium->grid;
    if (!sg_voxelize_grid_for(scene, resolution, g, err))
        return false;

    SgProgress progress;
    sg_progress_begin(&progress, "voxelize", 0);
    double t0 = sg_seconds();
    sg_voxelize_surface(scene, g, options->threads);
    stats->seconds_voxelize = sg_seconds() - t0;
    sg_progress_update(&progress, 1);

    t0 = sg_seconds();
    stats->solid_voxels = sg_grid_count_nonzero(g);
    stats->air_voxels = sg_grid_count(g) - stats->solid_voxels;
    if (!medium_lights(scene, light_count, medium, err) || !keep_lit_air(scene, medium, stats, err)) {
        sg_medium_release(medium);
        return false;
    }
    stats->seconds_fill = sg_seconds() - t0;
    sg_progress_end(&progress);

    if (stats->sealed_lights == light_count || stats->medium_voxels == 0) {
        sg_medium_release(medium);
        return sg_fail(err, "%s: every light is sealed: no air in front of any emitter at "
                            "resolution %d", scene->path, resolution);
    }

    medium->resolution = resolution;
    medium->geometry_hash = scene->geometry_hash;
    snprintf(medium->scene_path, sizeof medium->scene_path, "%s", scene->path);
    if (scene->has_camera) {
        medium->has_camera = true;
        memcpy(medium->camera_position, scene->camera.position, sizeof medium->camera_position);
    }
    return true;
}
