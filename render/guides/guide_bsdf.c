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
    return path_guide_alloc(sizeof(PathGuide), &bsdf_ops, setup, err);
}

const PathGuideKind guide_bsdf_kind = {
    .mode = {.name = "bsdf", .help = "BSDF sampling (default without a cache)", .default_without_cache = true},
    .create = bsdf_create,
};
