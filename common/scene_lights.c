/* The scene's lights as the precompute and the guide count them (scene.h,
 * SgGuideLight). */
#include <math.h>
#include <string.h>

#include "color.h"
#include "scene.h"

static uint32_t kind_count(const SgScene *s, SgLightSourceKind kind)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->light_source_count; i++)
        n += s->light_sources[i].kind == kind;
    return n;
}

bool sg_scene_lit_from_outside(const SgScene *s)
{
    return kind_count(s, SG_LIGHT_INFINITE) || kind_count(s, SG_LIGHT_DISTANT);
}

uint32_t sg_scene_guide_light_count(const SgScene *s)
{
    return s->light_count + kind_count(s, SG_LIGHT_POINT) + kind_count(s, SG_LIGHT_SPOT) +
           (kind_count(s, SG_LIGHT_INFINITE) ? 1u : 0u) +
           kind_count(s, SG_LIGHT_DISTANT);
}

static double bounding_radius2(const SgScene *s)
{
    double r2 = 0;
    for (int a = 0; a < 3; a++)
        r2 += 0.25 * (s->bounds_max[a] - s->bounds_min[a]) * (s->bounds_max[a] - s->bounds_min[a]);
    return r2;
}

SgGuideLight sg_scene_guide_light(const SgScene *s, uint32_t i)
{
    SgGuideLight g;
    memset(&g, 0, sizeof g);
    if (i < s->light_count) {
        const SgLight *l = &s->lights[i];
        g.kind = SG_GUIDE_LIGHT_AREA;
        g.index = i;
        memcpy(g.position, l->position, sizeof g.position);
        memcpy(g.normal, l->normal, sizeof g.normal);
        g.power = l->power;
        return g;
    }
    i -= s->light_count;
    for (uint32_t k = 0; k < s->light_source_count; k++) {
        const SgLightSource *l = &s->light_sources[k];
        if (l->kind != SG_LIGHT_POINT && l->kind != SG_LIGHT_SPOT)
            continue;
        if (i-- > 0)
            continue;
        g.kind = SG_GUIDE_LIGHT_POINT;
        g.index = k;
        memcpy(g.position, l->position, sizeof g.position);
        if (l->kind == SG_LIGHT_SPOT)
            memcpy(g.normal, l->direction, sizeof g.normal);
        double lum = sg_luminance(l->rgb[0], l->rgb[1], l->rgb[2]);
        g.power = l->kind == SG_LIGHT_POINT ? 4 * M_PI * lum
                                            : 2 * M_PI * lum * (1 - 0.5 * (l->cos_falloff_start + l->cos_cone));
        return g;
    }
    /* the outside: what the skies send through a disk of the scene's size
     * (pi r^2 pi L) */
    double r2 = bounding_radius2(s);
    if (kind_count(s, SG_LIGHT_INFINITE)) {
        if (i-- == 0) {
            g.kind = SG_GUIDE_LIGHT_OUTSIDE;
            for (uint32_t k = 0; k < s->light_source_count; k++) {
                const SgLightSource *l = &s->light_sources[k];
                if (l->kind == SG_LIGHT_INFINITE)
                    g.power += M_PI * r2 * M_PI * sg_luminance(l->rgb[0], l->rgb[1], l->rgb[2]);
            }
            return g;
        }
    }
    /* each sun: pi r^2 E */
    for (uint32_t k = 0; k < s->light_source_count; k++) {
        const SgLightSource *l = &s->light_sources[k];
        if (l->kind != SG_LIGHT_DISTANT || i-- > 0)
            continue;
        g.kind = SG_GUIDE_LIGHT_SUN;
        g.index = k;
        memcpy(g.normal, l->direction, sizeof g.normal);
        g.power = M_PI * r2 * sg_luminance(l->rgb[0], l->rgb[1], l->rgb[2]);
        return g;
    }
    return g;
}
