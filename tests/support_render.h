/* Test support for the renderer: analytic scenes built in memory. */
#ifndef SG_SUPPORT_RENDER_H
#define SG_SUPPORT_RENDER_H

#include <stdbool.h>

#include "render/renderer.h"
#include "scene.h"

SgScene *sgt_scene_new(void);
/* Frees a scene made here (not one from sg_scene_load). */
void sgt_scene_free(SgScene *s);
uint32_t sgt_add_material(SgScene *s, SgMaterialType type, const float albedo[3],
                          const float emission[3]);
SgMaterial *sgt_material(SgScene *s, uint32_t m);
/* Quad c0 c1 c2 c3 (two triangles), normal (c1 - c0) x (c2 - c0); an
 * emissive material makes it one light. */
void sgt_add_quad(SgScene *s, const double c[4][3], uint32_t material);
/* Axis-aligned box with normals pointing inward, each face one quad. */
void sgt_add_box_inside(SgScene *s, const double lo[3], const double hi[3], uint32_t material);
void sgt_set_camera(SgScene *s, const double pos[3], const double at[3], const double up[3],
                    double fov, int width, int height);
/* Bounds and lights (one per emissive quad); call once when done. */
void sgt_finish(SgScene *s);
/* The usual ending: a camera at pos looking at `at`, +y up, then
 * sgt_finish. */
void sgt_finish_looking(SgScene *s, const double pos[3], const double at[3], double fov, int width, int height);
/* Transforms every position by p * scale + offset (camera too). */
void sgt_scale_offset(SgScene *s, double scale, const double offset[3]);

/* The furnace: a closed box (-1,-1,-1)-(1,1.5,2), inward normals, albedo
 * 0.5, emission 0.5 (L = 0.5 + 0.5 L = 1 everywhere), a 32x24 camera inside. */
SgScene *sgt_furnace_scene(void);

/* Two rooms, 4x2x2, parted at x = 2 by a wall with a window (y, z in
 * [0.75, 1.25]): a light on room A's ceiling, out of sight from room B,
 * which a 40x30 camera looks into; B's light comes through the window. */
SgScene *sgt_window_rooms(void);

/* A guide stand-in (SgImportanceFn) whose importance point is always the
 * same world position: ctx is an SgtFixedPoint. */
typedef struct SgtFixedPoint {
    double point[3];
} SgtFixedPoint;
bool sgt_fixed_point_guide(void *ctx, const double p[3], uint32_t light, double q[3]);

/* `passes` more passes of r (an image of `pixels` pixels): the mean of
 * channel 0 over every sample and its standard error from the samples'
 * spread (they are independent). */
typedef struct SgtSampleMean {
    double mean, std_error;
} SgtSampleMean;
/* The renderer's statistics (sg_renderer_stats), as a value. */
static inline SgRenderStats sgt_stats(const SgRenderer *r)
{
    SgRenderStats st;
    sg_renderer_stats(r, &st);
    return st;
}

/* The scene a file of `text` named `name` (its extension says the format)
 * loads as; NULL with err set where the loader refuses it. */
SgScene *sgt_scene_from_text(const char *name, const char *text, SgError *err);
/* The scene file at path, which must load: the test fails with the
 * loader's message where it does not. */
SgScene *sgt_load_ok(const char *path);

/* A pbrt-v4 scene's start: an 8x8 camera over a 2x2 floor, after WorldBegin. */
#define SGT_PBRT_ROOM                                                                                             \
    "Scale -1 1 1\nLookAt 0 1 -3  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nFilm \"rgb\" "     \
    "\"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n"                                       \
    "Shape \"trianglemesh\" \"point3 P\" [-1 0 -1 1 0 -1 1 0 1 -1 0 1] \"integer indices\" [0 1 2 0 2 3]\n"

SgtSampleMean sgt_passes_mean(SgRenderer *r, int passes, size_t pixels);

/* s's default options for `mode`, on 2 threads with seed 7 (the tests' usual). */
SgRenderOptions sgt_options(const SgScene *s, SgSampling mode);

/* s rendered `passes` passes under o: its image, 3 floats a pixel (the
 * caller frees it), or NULL with err set. */
float *sgt_render_image(const SgScene *s, const SgRenderOptions *o, int passes, SgError *err);
/* The same under s's default options on 2 threads, which *o receives. */
float *sgt_render_default(const SgScene *s, SgRenderOptions *o, int passes, SgError *err);

#endif
