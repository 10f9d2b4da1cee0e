/* The pinhole camera in the renderer's local frame (world minus the
 * scene's centre, so that float coordinates keep their precision). */
#ifndef SG_RENDER_CAMERA_H
#define SG_RENDER_CAMERA_H

#include "scene.h"
#include "vecmath.h"

typedef struct Camera {
    Vec3 pos, forward, right, up;
    float tan_half_fov, aspect;
    int width, height;
} Camera;

/* From the scene's camera; `centre` is the world position of the local origin. */
void camera_init(Camera *c, const SgCamera *sc, const double centre[3], int width, int height);

/* The unit direction through image position (x + jx, y + jy), y down. */
static inline Vec3 camera_ray(const Camera *c, int x, int y, float jx, float jy)
{
    float sx = (2.0f * ((float)x + jx) / (float)c->width - 1.0f) * c->tan_half_fov * c->aspect;
    float sy = (1.0f - 2.0f * ((float)y + jy) / (float)c->height) * c->tan_half_fov;
    return v3_normalize(v3_add(c->forward, v3_add(v3_scale(c->right, sx), v3_scale(c->up, sy))));
}

#endif
