/* Our render of a scene against another renderer's converged image of it,
 * region by region, on the pixels whose surface we can render as its
 * author meant: the camera ray's first hit has a material none of whose
 * textures is missing (and is not a light seen directly).
 *   build/release/bench/reference_compare SCENE OURS.exr REFERENCE.exr
 * The reference may be larger by a whole factor (box-filtered down). Prints
 * "key value" lines: the mask's share of the image, the mean per channel
 * of ours over the reference on the mask and on the whole image, and the
 * largest deviation among the 4 x 4 regions that are mostly masked. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "image_io.h"
#include "render/camera.h"
#include "render/geometry.h"
#include "scene_load.h"

#define REGIONS 4

/* Does texture t (1 + index) or any it is made of lack its image? */
static bool texture_missing(const SgScene *s, uint32_t t)
{
    if (!t || t > s->texture_count)
        return false;
    const SgTexture *tex = &s->textures[t - 1];
    if (tex->kind == SG_TEXTURE_IMAGE && !tex->path)
        return true;
    for (int k = 0; k < 3; k++)
        if (tex->input[k].texture && tex->input[k].texture < t && texture_missing(s, tex->input[k].texture))
            return true;
    return false;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: reference_compare SCENE OURS.exr REFERENCE.exr\n");
        return 2;
    }
    SgError err = {0};
    SgScene *s = sg_scene_load(argv[1], &err);
    int w, h, rw, rh;
    float *ours = NULL, *ref = NULL;
    if (!s || !sg_image_read(argv[2], &w, &h, &ours, &err) || !sg_image_read(argv[3], &rw, &rh, &ref, &err)) {
        fprintf(stderr, "reference_compare: %s\n", err.message);
        return 1;
    }
    if (rw % w || rh % h || rw / w != rh / h) {
        fprintf(stderr, "reference_compare: %s is %dx%d, not a whole multiple of %dx%d\n", argv[3], rw, rh, w, h);
        return 1;
    }
    int f = rw / w;
    Geometry geo;
    if (!geometry_init(&geo, s, argv[1], &err) || !geometry_build(&geo, argv[1], &err)) {
        fprintf(stderr, "reference_compare: %s\n", err.message);
        return 1;
    }
    Camera cam;
    camera_init(&cam, &s->camera, geo.centre, w, h);
    double sum_ours[3] = {0}, sum_ref[3] = {0}, all_ours[3] = {0}, all_ref[3] = {0};
    double reg_ours[REGIONS][REGIONS][3] = {{{0}}}, reg_ref[REGIONS][REGIONS][3] = {{{0}}};
    long masked = 0, reg_count[REGIONS][REGIONS] = {{0}};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double r[3] = {0, 0, 0};
            for (int dy = 0; dy < f; dy++)
                for (int dx = 0; dx < f; dx++)
                    for (int c = 0; c < 3; c++)
                        r[c] += ref[3 * ((size_t)(y * f + dy) * rw + (size_t)(x * f + dx)) + c] / (double)(f * f);
            const float *o = ours + 3 * ((size_t)y * w + x);
            for (int c = 0; c < 3; c++) {
                all_ours[c] += o[c];
                all_ref[c] += r[c];
            }
            Hit hit = intersect(&geo, cam.pos, camera_ray(&cam, x, y, 0.5f, 0.5f), INFINITY);
            if (!hit.found)
                continue;
            const SgMaterial *m = &s->materials[geo.tris[hit.tri].material];
            bool emissive = m->emission[0] > 0 || m->emission[1] > 0 || m->emission[2] > 0;
            if (emissive || texture_missing(s, m->diffuse_texture))
                continue;
            masked++;
            int ry = y * REGIONS / h, rx = x * REGIONS / w;
            reg_count[ry][rx]++;
            for (int c = 0; c < 3; c++) {
                sum_ours[c] += o[c];
                sum_ref[c] += r[c];
                reg_ours[ry][rx][c] += o[c];
                reg_ref[ry][rx][c] += r[c];
            }
        }
    printf("mask %.3f\n", (double)masked / ((double)w * h));
    printf("ratio_masked %.4f %.4f %.4f\n", sum_ours[0] / sum_ref[0], sum_ours[1] / sum_ref[1],
           sum_ours[2] / sum_ref[2]);
    printf("ratio_all %.4f %.4f %.4f\n", all_ours[0] / all_ref[0], all_ours[1] / all_ref[1],
           all_ours[2] / all_ref[2]);
    /* regions mostly on the mask: the one furthest from 1 (luminance-free: per channel) */
    double worst = 1.0;
    int worst_x = -1, worst_y = -1;
    long per_region = (long)w * h / (REGIONS * REGIONS);
    for (int ry = 0; ry < REGIONS; ry++)
        for (int rx = 0; rx < REGIONS; rx++) {
            if (reg_count[ry][rx] * 2 < per_region)
                continue;
            for (int c = 0; c < 3; c++) {
                double q = reg_ours[ry][rx][c] / reg_ref[ry][rx][c];
                if (reg_ref[ry][rx][c] > 0 && fabs(log(q)) > fabs(log(worst))) {
                    worst = q;
                    worst_x = rx;
                    worst_y = ry;
                }
            }
        }
    printf("worst_region %.4f at %d,%d of %dx%d\n", worst, worst_x, worst_y, REGIONS, REGIONS);
    geometry_free(&geo);
    free(ours);
    free(ref);
    sg_scene_free(s);
    return 0;
}
