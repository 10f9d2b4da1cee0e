#include "lights.h"

#include <stdlib.h>

bool light_set_init(LightSet *ls, const SgScene *s, const Vec3 *vertices, const Material *materials,
                    const double *follow_weight, const char *path, SgError *err)
{
    ls->count = s->light_count;
    if (!ls->count)
        return true;
    ls->lights = calloc(ls->count, sizeof *ls->lights);
    ls->cdf = calloc(ls->count, sizeof *ls->cdf);
    ls->follow_cdf = calloc(ls->count, sizeof *ls->follow_cdf);
    uint32_t total_tris = 0;
    for (uint32_t l = 0; l < s->light_count; l++)
        total_tris += s->lights[l].triangle_count;
    ls->tris = calloc(total_tris ? total_tris : 1, sizeof *ls->tris);
    ls->tri_cdf = calloc(total_tris ? total_tris : 1, sizeof *ls->tri_cdf);
    if (!ls->lights || !ls->cdf || !ls->follow_cdf || !ls->tris || !ls->tri_cdf)
        return sg_fail(err, "%s: out of memory for the light table", path);
    double total_power = 0.0;
    double *power = calloc(ls->count, sizeof *power);
    if (!power)
        return sg_fail(err, "%s: out of memory", path);
    uint32_t k = 0;
    for (uint32_t l = 0; l < s->light_count; l++) {
        const SgLight *L = &s->lights[l];
        LightTable *lt = &ls->lights[l];
        lt->first = k;
        double area = 0.0;
        for (uint32_t i = 0; i < L->triangle_count; i++) {
            uint32_t t = s->light_triangles[L->first_triangle + i];
            if (t >= s->triangle_count) {
                free(power);
                return sg_fail(err, "%s: light %u names triangle %u of %u", path, l, t,
                               s->triangle_count);
            }
            const Vec3 *v = vertices;
            const uint32_t *id = s->indices + 3 * t;
            float a = 0.5f * v3_length(v3_cross(v3_sub(v[id[1]], v[id[0]]), v3_sub(v[id[2]], v[id[0]])));
            area += a;
            ls->tris[k] = t;
            ls->tri_cdf[k] = area;
            k++;
        }
        lt->count = k - lt->first;
        for (uint32_t i = lt->first; i < k; i++)
            ls->tri_cdf[i] = area > 0 ? ls->tri_cdf[i] / area : (double)(i - lt->first + 1) / lt->count;
        lt->inv_area = area > 0 ? (float)(1.0 / area) : 0.0f;
        /* power from what the renderer will emit: the material's emission */
        Vec3 e = v3(0, 0, 0);
        if (L->triangle_count) {
            uint32_t t0 = s->light_triangles[L->first_triangle];
            e = materials[s->triangle_material[t0]].emission;
        }
        power[l] = area > 0 ? area * luminance(e) : 0.0;
        total_power += power[l];
    }
    double acc = 0.0;
    for (uint32_t l = 0; l < ls->count; l++) {
        ls->lights[l].pick_pdf = total_power > 0 ? power[l] / total_power : 0.0;
        acc += ls->lights[l].pick_pdf;
        ls->cdf[l] = acc;
    }
    /* guide: which light to follow */
    const double *w = follow_weight ? follow_weight : power;
    double wsum = 0.0;
    for (uint32_t l = 0; l < ls->count; l++)
        wsum += w[l] > 0 ? w[l] : 0.0;
    acc = 0.0;
    for (uint32_t l = 0; l < ls->count; l++) {
        acc += wsum > 0 && w[l] > 0 ? w[l] / wsum : 0.0;
        ls->follow_cdf[l] = acc;
    }
    free(power);
    return true;
}

void light_set_free(LightSet *ls)
{
    free(ls->lights);
    free(ls->cdf);
    free(ls->tris);
    free(ls->tri_cdf);
    free(ls->follow_cdf);
    *ls = (LightSet){0};
}
