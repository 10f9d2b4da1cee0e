/* The scenes of tests/data/pbrt-lights/ (one pbrt-v4 light each: skies,
 * suns, point and spot lights, disk, sphere and cylinder lamps, a sky
 * through a window with and without its portal) rendered small by bin/render's
 * renderer, each channel's image mean against pbrt-v4's (docs/render.md,
 * "Compared with pbrt-v4"). The scenes are loaded as files, so the pbrt
 * loader's reading of each light and of the Integrator's maxdepth is
 * checked along with the renderer. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/renderer.h"
#include "scene_load.h"
#include "support_files.h"
#include "support_render.h"

/* pbrt-v4's means, linear RGB over its whole 160x120 image (the mean over
 * the film does not depend on the resolution, so ours is rendered at
 * 40x30), and their standard errors from 4 seeds:
 *   pbrt --nthreads 2 --spp 512 --seed K --outfile SCENE-sK.exr SCENE.pbrt
 * for K = 1..4, in tests/data/pbrt-lights/, with pbrt-v4 at commit
 * 5f7a6068 (mmp/pbrt-v4, CPU build); the means by OpenImageIO. */
typedef struct PbrtReference {
    const char *scene;
    double mean[3], std_error[3];
    int passes; /* ours: passes of 1 sample a pixel at 40x30 */
} PbrtReference;

static const PbrtReference references[] = {
    {"sky-constant", {0.706853, 0.706831, 0.706815}, {7.14e-06, 9.82e-06, 8.00e-06}, 32},
    {"sky-coloured", {0.632463, 0.834616, 1.038025}, {4.49e-06, 2.12e-05, 2.36e-05}, 32},
    {"sky-map", {0.903167, 0.921082, 0.934413}, {1.92e-06, 6.48e-06, 2.10e-05}, 128},
    {"distant-illuminance", {0.334716, 0.325741, 0.320664}, {7.38e-06, 5.53e-06, 9.76e-06}, 32},
    {"distant-L", {0.215510, 0.190115, 0.146030}, {5.95e-06, 3.96e-06, 3.82e-06}, 32},
    {"point-I", {0.037928, 0.036246, 0.035295}, {1.13e-06, 9.52e-07, 1.37e-06}, 32},
    {"point-power", {0.058934, 0.044484, 0.032110}, {9.60e-07, 7.83e-07, 6.18e-07}, 32},
    {"spot", {0.035085, 0.031335, 0.029216}, {1.75e-06, 1.38e-06, 2.06e-06}, 32},
    {"area-disk", {0.046125, 0.043694, 0.042316}, {1.91e-06, 1.52e-06, 3.91e-06}, 32},
    {"area-sphere", {0.088159, 0.072576, 0.057615}, {3.52e-06, 3.12e-06, 1.44e-05}, 256},
    {"area-cylinder", {0.196131, 0.194545, 0.193641}, {1.17e-05, 3.83e-06, 1.98e-05}, 512},
    {"room-window", {0.114340, 0.079857, 0.099044}, {7.87e-06, 6.90e-06, 1.87e-05}, 1024},
    {"room-portal", {0.114310, 0.079850, 0.099044}, {2.27e-06, 2.68e-06, 6.41e-06}, 512},
};

/* What spectral rendering may move a mean by, on top of the noise: pbrt-v4
 * turns each RGB into a spectrum and back, within 0.1% for a light seen
 * directly and exactly for a grey floor under a white sky (0.49999 for
 * 0.5), but a coloured light on a coloured surface is a product of spectra,
 * not of RGBs: the orange pillar under point-power's light (1 0.8 0.6) is
 * 3% redder and 8% bluer in ours, 0.36% of the image's red mean. */
#define SPECTRAL_ALLOWANCE 0.005
/* The passes' spread underestimates a mean's standard error (point-I at
 * 32 passes: 4e-5 from the passes, 5.9e-5 over 10 seeds), hence 5 of it. */
#define SIGMAS 5.0

/* Each channel's image mean over `passes` passes of bsdf sampling (seed 7,
 * 2 threads), and its standard error from the passes' spread. */
static void render_means(const char *scene, int passes, double mean[3], double std_error[3])
{
    SgError err = {0};
    SgScene *s = sg_scene_load(sg_test_source_path(scene), &err);
    cr_assert(s, "%s", err.message);
    SgRenderOptions o = sgt_options(s, SG_SAMPLING_BSDF);
    o.width = 40;
    o.height = 30;
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert(r, "renderer: %s", err.message);
    size_t pixels = (size_t)o.width * o.height;
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int p = 0; p < passes; p++) {
        sg_renderer_pass(r);
        const float *last = sg_renderer_last_pass(r);
        double m[3] = {0, 0, 0};
        for (size_t i = 0; i < pixels; i++)
            for (int c = 0; c < 3; c++)
                m[c] += last[3 * i + c];
        for (int c = 0; c < 3; c++) {
            m[c] /= (double)pixels;
            sum[c] += m[c];
            sum2[c] += m[c] * m[c];
        }
    }
    for (int c = 0; c < 3; c++) {
        mean[c] = sum[c] / passes;
        std_error[c] = sqrt(fmax(0.0, sum2[c] / passes - mean[c] * mean[c]) / (passes - 1));
    }
    sg_renderer_free(r);
    sg_scene_free(s);
}

static void check_against_pbrt(const char *name)
{
    const PbrtReference *ref = NULL;
    for (size_t i = 0; i < sizeof references / sizeof *references; i++)
        if (!strcmp(references[i].scene, name))
            ref = &references[i];
    cr_assert(ref, "no pbrt-v4 reference for %s", name);
    char path[256];
    snprintf(path, sizeof path, "tests/data/pbrt-lights/%s.pbrt", name);
    double mean[3], se[3];
    render_means(path, ref->passes, mean, se);
    cr_log_info("%s: ours %.5f %.5f %.5f +- %.5f %.5f %.5f, pbrt-v4 %.5f %.5f %.5f", name, mean[0], mean[1], mean[2],
                se[0], se[1], se[2], ref->mean[0], ref->mean[1], ref->mean[2]);
    for (int c = 0; c < 3; c++) {
        double sigma = sqrt(se[c] * se[c] + ref->std_error[c] * ref->std_error[c]);
        double tol = SIGMAS * sigma + SPECTRAL_ALLOWANCE * ref->mean[c];
        cr_expect(fabs(mean[c] - ref->mean[c]) <= tol,
                  "%s channel %d: ours %.5f +- %.5f, pbrt-v4 %.5f +- %.5f (%+.1f sigma; allowed %.0f sigma + %.1f%%)",
                  name, c, mean[c], se[c], ref->mean[c], ref->std_error[c], (mean[c] - ref->mean[c]) / sigma,
                  SIGMAS, 100 * SPECTRAL_ALLOWANCE);
    }
}

Test(pbrt_lights, sky_constant) { check_against_pbrt("sky-constant"); }
Test(pbrt_lights, sky_coloured) { check_against_pbrt("sky-coloured"); }
Test(pbrt_lights, sky_map) { check_against_pbrt("sky-map"); }
Test(pbrt_lights, distant_illuminance) { check_against_pbrt("distant-illuminance"); }
Test(pbrt_lights, distant_L) { check_against_pbrt("distant-L"); }
Test(pbrt_lights, point_I) { check_against_pbrt("point-I"); }
Test(pbrt_lights, point_power) { check_against_pbrt("point-power"); }
Test(pbrt_lights, spot) { check_against_pbrt("spot"); }
Test(pbrt_lights, area_disk) { check_against_pbrt("area-disk"); }
Test(pbrt_lights, area_sphere) { check_against_pbrt("area-sphere"); }
Test(pbrt_lights, area_cylinder) { check_against_pbrt("area-cylinder"); }
Test(pbrt_lights, room_window) { check_against_pbrt("room-window"); }
Test(pbrt_lights, room_portal) { check_against_pbrt("room-portal"); }

/* ---- the pbrt loader's reading of the lights ----------------------------------- */

/* sgt_scene_from_text that must succeed. */
static SgScene *load_ok(const char *name, const char *text)
{
    SgError err = {0};
    SgScene *s = sgt_scene_from_text(name, text, &err);
    cr_assert(s, "%s", err.message);
    return s;
}

Test(pbrt_lights, pbrt_light_sources_read_as_pbrt_v4_does)
{
    SgScene *s = load_ok("sources.pbrt",
                           SGT_PBRT_ROOM "LightSource \"point\" \"rgb I\" [1 2 3] \"float power\" 100 \"point3 from\" [0 2 0]\n"
                                     "AttributeBegin\nTranslate 1 0 0\n"
                                     "LightSource \"spot\" \"rgb I\" [1 1 1] \"float scale\" 2 \"float coneangle\" 40 "
                                     "\"float conedeltaangle\" 10 \"point3 from\" [0 3 0] \"point3 to\" [0 0 0]\n"
                                     "AttributeEnd\n"
                                     "LightSource \"distant\" \"rgb L\" [1 1 1] \"float illuminance\" 5 "
                                     "\"point3 from\" [0 1 1] \"point3 to\" [0 0 0]\n"
                                     "Rotate -90 1 0 0\n"
                                     "LightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5] \"float scale\" 2 "
                                     "\"point3 portal\" [-1 -1 2  1 -1 2  1 1 2  -1 1 2]\n");
    cr_assert_eq(s->light_source_count, 4);
    const SgLightSource *p = &s->light_sources[0], *spot = &s->light_sources[1], *sun = &s->light_sources[2],
                        *sky = &s->light_sources[3];
    cr_expect(p->kind == SG_LIGHT_POINT && fabs(p->position[1] - 2) < 1e-12);
    cr_expect(fabsf(p->rgb[2] - (float)(3 * 100 / (4 * M_PI))) < 1e-4f, "power over 4 pi: %g", p->rgb[2]);
    cr_expect(spot->kind == SG_LIGHT_SPOT && fabs(spot->position[0] - 1) < 1e-12 && fabs(spot->direction[1] + 1) < 1e-12);
    cr_expect(fabs(spot->cos_cone - cos(40 * M_PI / 180)) < 1e-12 && fabs(spot->cos_falloff_start - cos(30 * M_PI / 180)) < 1e-12);
    cr_expect(spot->rgb[0] == 2.0f);
    cr_expect(sun->kind == SG_LIGHT_DISTANT && sun->rgb[0] == 5.0f);
    cr_expect(fabs(sun->direction[1] + sqrt(0.5)) < 1e-9 && fabs(sun->direction[2] + sqrt(0.5)) < 1e-9);
    cr_expect(sky->kind == SG_LIGHT_INFINITE && sky->rgb[0] == 1.0f && sky->has_portal);
    /* Rotate -90 about x takes light space's z (up) to world +y */
    cr_expect(fabs(sky->light_to_world[1][2] - 1) < 1e-9, "light z to world y: %g", sky->light_to_world[1][2]);
    /* but the portal's points are world space, whatever the transform, as
     * pbrt-v4 reads them (its lights.cpp maps them by RenderFromWorld) */
    cr_expect(fabs(sky->portal[0][0] + 1) < 1e-9 && fabs(sky->portal[0][1] + 1) < 1e-9 && fabs(sky->portal[0][2] - 2) < 1e-9,
              "portal in world space: %g %g %g", sky->portal[0][0], sky->portal[0][1], sky->portal[0][2]);
    sg_scene_free(s);
}

Test(pbrt_lights, pbrt_disk_lamp_has_its_true_area)
{
    SgScene *s = load_ok("disk.pbrt",
                           SGT_PBRT_ROOM "AttributeBegin\nTranslate 0 2 0\nRotate 90 1 0 0\n"
                                     "AreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
                                     "Shape \"disk\" \"float radius\" 0.25\nAttributeEnd\n"
                                     "Shape \"sphere\" \"float radius\" 0.3\nShape \"cylinder\" \"float radius\" 0.1\n");
    cr_assert_eq(s->light_count, 1);
    cr_expect(fabs(s->lights[0].area - M_PI * 0.0625) < 1e-9, "disk area %.12g", s->lights[0].area);
    /* Rotate 90 about x takes the disk's +z to -y: it shines down */
    cr_expect(s->lights[0].normal[1] < -0.999, "disk normal %g", s->lights[0].normal[1]);
    cr_expect_eq(s->warning_count, 0, "no shape left out: %s", s->warning_count ? s->warnings[0] : "");
    cr_expect_eq(s->degenerate_dropped, 0, "the meshes hold no zero-area triangle (a sphere's poles)");
    sg_scene_free(s);
}
