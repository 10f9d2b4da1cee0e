#include "path_guide.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* The modes in SG_SAMPLING_MODES's order, each the kind its guide file defines. */
#define PATH_GUIDE_KIND_ENTRY(id, name, file) [SG_SAMPLING_##id] = &guide_##file##_kind,
static const PathGuideKind *const kinds[SG_SAMPLING_COUNT] = {SG_SAMPLING_MODES(PATH_GUIDE_KIND_ENTRY)};
#undef PATH_GUIDE_KIND_ENTRY

const SgSamplingMode *sg_sampling_mode(SgSampling s)
{
    return (int)s >= 0 && s < SG_SAMPLING_COUNT ? &kinds[s]->mode : NULL;
}

const char *sg_sampling_name(SgSampling s)
{
    const SgSamplingMode *m = sg_sampling_mode(s);
    return m ? m->name : "?";
}

bool sg_sampling_parse(const char *name, SgSampling *s)
{
    for (int i = 0; i < SG_SAMPLING_COUNT; i++)
        if (strcmp(name, kinds[i]->mode.name) == 0) {
            *s = (SgSampling)i;
            return true;
        }
    return false;
}

SgSampling sg_sampling_default(bool has_cache)
{
    for (int i = 0; i < SG_SAMPLING_COUNT; i++)
        if (has_cache ? kinds[i]->mode.default_with_cache : kinds[i]->mode.default_without_cache)
            return (SgSampling)i;
    return (SgSampling)0;
}

PathGuide *path_guide_create(SgSampling mode, const PathGuideSetup *setup, SgError *err)
{
    const SgSamplingMode *m = sg_sampling_mode(mode);
    if (!m)
        return sg_fail(err, "%s: unknown sampling mode %d", setup->path, (int)mode), NULL;
    if (m->available) {
        SgError e = {0};
        if (!m->available(&e))
            return sg_fail(err, "%s: --sampling %s: %s", setup->path, m->name, e.message), NULL;
    }
    if (m->uses_cache && !setup->opt->importance.importance_point)
        return sg_fail(err, "%s: %s sampling needs an importance cache", setup->path, m->name), NULL;
    return kinds[mode]->create(setup, err);
}

void *path_guide_alloc(size_t size, const PathGuideOps *ops, const PathGuideSetup *setup, SgError *err)
{
    PathGuide *g = calloc(1, size);
    if (!g)
        return sg_fail(err, "%s: out of memory", setup->path), NULL;
    g->ops = ops;
    return g;
}

void path_guide_free(PathGuide *g)
{
    if (g)
        g->ops->destroy(g);
}

void path_guide_stats(const PathGuide *g, GuideStats *s)
{
    *s = (GuideStats){.guided_fraction = -1.0};
    if (g && g->ops->stats)
        g->ops->stats(g, s);
}
