/* bsdf: every bounce from the material's own sampler; the baseline the
 * other guides are measured against. */
#include <stdlib.h>

#include "path_guide.h"

static void bsdf_destroy(PathGuide *g) { free(g); }

static const PathGuideOps bsdf_ops = {
    .name = "bsdf",
    .destroy = bsdf_destroy,
    .pdf = guide_bsdf_pdf,
    .sample = guide_bsdf_sample,
};

static PathGuide *bsdf_create(const PathGuideSetup *setup, SgError *err)
{
    PathGuide *g = calloc(1, sizeof *g);
    if (!g)
        return sg_fail(err, "%s: out of memory", setup->path), NULL;
    g->ops = &bsdf_ops;
    return g;
}

const PathGuideKind guide_bsdf_kind = {
    .mode = {.name = "bsdf", .help = "BSDF sampling (default without a cache)", .default_without_cache = true},
    .create = bsdf_create,
};
