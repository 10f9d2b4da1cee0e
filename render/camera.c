#include "camera.h"

#include <math.h>

void camera_init(Camera *cam, const SgCamera *c, const double centre[3], int width, int height)
{
    double pos[3], at[3];
    for (int i = 0; i < 3; i++) {
        pos[i] = c->position[i] - centre[i];
        at[i] = c->look_at[i] - centre[i];
    }
    cam->pos = v3((float)pos[0], (float)pos[1], (float)pos[2]);
    double f[3] = {at[0] - pos[0], at[1] - pos[1], at[2] - pos[2]};
    double fl = d3_length(f);
    Vec3 forward = fl > 0 ? v3((float)(f[0] / fl), (float)(f[1] / fl), (float)(f[2] / fl)) : v3(0, 0, -1);
    Vec3 up = v3_normalize(v3((float)c->up[0], (float)c->up[1], (float)c->up[2]));
    Vec3 right = v3_cross(forward, up);
    if (v3_length(right) < 1e-6f) { /* up parallel to the view: pick any */
        Vec3 t, b;
        v3_basis(forward, &t, &b);
        right = t;
    }
    right = v3_normalize(right);
    cam->forward = forward;
    cam->right = right;
    cam->up = v3_cross(right, forward);
    double fov = c->fov_deg > 0 && c->fov_deg < 180 ? c->fov_deg : 60.0;
    cam->tan_half_fov = (float)tan(fov * M_PI / 360.0);
    cam->aspect = (float)width / (float)height;
    cam->width = width;
    cam->height = height;
}
