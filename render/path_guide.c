#include "path_guide.h"

#include <stddef.h>

/* One line per guide: the sampling mode the command line names, and the
 * file that implements it. */
static const PathGuideCreate guide_of_mode[SG_SAMPLING_COUNT] = {
    [SG_SAMPLING_BSDF] = guide_bsdf_create,
    [SG_SAMPLING_SKELETON] = guide_skeleton_rule_create,
    [SG_SAMPLING_GUIDED] = guide_mixture_create,
    [SG_SAMPLING_OPENPGL] = guide_openpgl_create,
};

PathGuide *path_guide_create(SgSampling mode, const PathGuideSetup *setup, SgError *err)
{
    if ((int)mode < 0 || mode >= SG_SAMPLING_COUNT || !guide_of_mode[mode])
        return sg_fail(err, "%s: unknown sampling mode %d", setup->path, (int)mode), NULL;
    return guide_of_mode[mode](setup, err);
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
