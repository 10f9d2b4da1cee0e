/* The peer's two bounce modes (--openpgl-mode ris|mis) and Open PGL's
 * guided roulette stay unbiased: the furnace's exact answer, agreement with
 * bsdf sampling on a glossy floor under a small light, RIS guiding glossy
 * vertices that MIS leaves alone, and a field that remembers its mode. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../render/guides/openpgl_field.h"
#include "../render/renderer.h"
#include "support_render.h"

typedef struct Estimate {
    double mean;      /* channel 0 over every sample */
    double std_error; /* from the samples' spread (the passes are independent given the field) */
    double lobe_share;
    uint64_t nonfinite;
} Estimate;

static void skip_without_openpgl(void)
{
    if (!sg_pgl_available())
        cr_skip_test("this build has no Open PGL (make openpgl builds it)");
}

/* `spp` passes of s under o: the mean of channel 0 over every sample. */
static Estimate estimate(const SgScene *s, const SgRenderOptions *o, int spp)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    SgtSampleMean m = sgt_passes_mean(r, spp, (size_t)o->width * o->height);
    Estimate e = {.mean = m.mean, .std_error = m.std_error};
    e.lobe_share = sgt_stats(r).lobe_share;
    e.nonfinite = sgt_stats(r).nonfinite;
    sg_renderer_free(r);
    return e;
}

static void openpgl_options(SgRenderOptions *o, const SgScene *s, SgOpenPglMode mode, SgRoulette roulette)
{
    sg_render_options_default(o, s);
    o->sampling = SG_SAMPLING_OPENPGL;
    o->openpgl_mode = mode;
    o->roulette = roulette;
    o->training_passes = 8;
}

/* ---- the furnace: radiance exactly 1 everywhere ---- */

static void furnace_case(SgOpenPglMode mode, SgRoulette roulette)
{
    skip_without_openpgl();
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o;
    openpgl_options(&o, s, mode, roulette);
    o.max_depth = 64; /* truncation error 0.5^64 */
    o.seed = 7;
    Estimate e = estimate(s, &o, 128);
    sgt_scene_free(s);
    cr_log_info("furnace openpgl %s, roulette %s: %.5f +- %.5f, guide drew %.3f", sg_openpgl_mode_name(mode),
                sg_roulette_name(roulette), e.mean, e.std_error, e.lobe_share);
    cr_assert_eq(e.nonfinite, 0);
    /* trained after 8 passes, the guide draws part of the bounces */
    cr_assert(e.lobe_share > 0.1 && e.lobe_share < 0.9, "the guide drew %.3f of the bounces", e.lobe_share);
    cr_assert(fabs(e.mean - 1.0) < 4.0 * e.std_error + 1e-6, "furnace openpgl %s: %.5f, expected 1 +- %.5f",
              sg_openpgl_mode_name(mode), e.mean, 4.0 * e.std_error);
    cr_assert(e.std_error < 0.02, "standard error %.4f is suspiciously large", e.std_error);
}

/* --roulette learned: Open PGL's guided roulette where the build has radiance caches */
Test(render_openpgl, furnace_ris, .timeout = 300) { furnace_case(SG_OPENPGL_RIS, SG_ROULETTE_LEARNED); }
Test(render_openpgl, furnace_ris_albedo_roulette, .timeout = 300) { furnace_case(SG_OPENPGL_RIS, SG_ROULETTE_ALBEDO); }
Test(render_openpgl, furnace_mis, .timeout = 300) { furnace_case(SG_OPENPGL_MIS, SG_ROULETTE_LEARNED); }

/* ---- a glossy floor under a small light, against bsdf ---- */

/* A closed grey room (diffuse walls, albedo 0.5) with a small square light
 * under its ceiling and a glossy floor (Phong, kd 0.2, ks 0.6, exponent
 * 30), seen from a corner: most of what the floor shows comes by its lobe. */
static SgScene *glossy_room(void)
{
    SgScene *s = sgt_scene_new();
    const float grey[3] = {0.5f, 0.5f, 0.5f}, black[3] = {0, 0, 0}, lamp[3] = {20, 20, 20};
    uint32_t wall = sgt_add_material(s, SG_MATERIAL_DIFFUSE, grey, NULL);
    uint32_t light = sgt_add_material(s, SG_MATERIAL_DIFFUSE, black, lamp);
    uint32_t floor = sgt_add_material(s, SG_MATERIAL_GLOSSY, grey, NULL);
    SgMaterial *fm = sgt_material(s, floor);
    for (int i = 0; i < 3; i++) {
        fm->diffuse[i] = 0.2f;
        fm->specular[i] = 0.6f;
    }
    fm->exponent = 30.0f;
    const double lo[3] = {0, 0, 0}, hi[3] = {2, 2, 2};
    sgt_add_box_inside(s, lo, hi, wall);
    const double floor_q[4][3] = {{0, 1e-3, 0}, {0, 1e-3, 2}, {2, 1e-3, 2}, {2, 1e-3, 0}};
    sgt_add_quad(s, floor_q, floor);
    const double lamp_q[4][3] = {{0.8, 1.95, 0.8}, {1.2, 1.95, 0.8}, {1.2, 1.95, 1.2}, {0.8, 1.95, 1.2}};
    sgt_add_quad(s, lamp_q, light);
    const double pos[3] = {0.2, 1.2, 0.2}, at[3] = {1.4, 0.0, 1.4};
    sgt_finish_looking(s, pos, at, 70, 16, 12);
    return s;
}

static void agreement_case(SgOpenPglMode mode, SgRoulette roulette)
{
    skip_without_openpgl();
    SgScene *s = glossy_room();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    o.seed = 3;
    Estimate ref = estimate(s, &o, 1024);
    openpgl_options(&o, s, mode, roulette);
    o.seed = 4;
    Estimate e = estimate(s, &o, 1024);
    sgt_scene_free(s);
    double se = sqrt(ref.std_error * ref.std_error + e.std_error * e.std_error);
    cr_log_info("glossy room: bsdf %.5f +- %.5f, openpgl %s roulette %s %.5f +- %.5f, guide drew %.3f", ref.mean,
                ref.std_error, sg_openpgl_mode_name(mode), sg_roulette_name(roulette), e.mean, e.std_error,
                e.lobe_share);
    cr_assert_eq(e.nonfinite, 0);
    cr_assert_gt(e.lobe_share, 0.05, "the guide drew %.3f of the bounces", e.lobe_share);
    cr_assert(fabs(e.mean - ref.mean) < 3.0 * se, "openpgl %s: %.5f against bsdf's %.5f (3 standard errors %.5f)",
              sg_openpgl_mode_name(mode), e.mean, ref.mean, 3.0 * se);
}

Test(render_openpgl, glossy_room_ris_agrees_with_bsdf, .timeout = 600)
{
    agreement_case(SG_OPENPGL_RIS, SG_ROULETTE_LEARNED);
}
Test(render_openpgl, glossy_room_ris_albedo_roulette_agrees_with_bsdf, .timeout = 600)
{
    agreement_case(SG_OPENPGL_RIS, SG_ROULETTE_ALBEDO);
}
Test(render_openpgl, glossy_room_mis_agrees_with_bsdf, .timeout = 600)
{
    agreement_case(SG_OPENPGL_MIS, SG_ROULETTE_LEARNED);
}

/* ---- RIS guides glossy vertices, MIS does not ---- */

/* The furnace with every wall a Phong lobe alone (no diffuse part). */
static double glossy_furnace_share(SgOpenPglMode mode)
{
    SgScene *s = sgt_furnace_scene();
    SgMaterial *m = sgt_material(s, s->triangle_material[0]);
    m->type = SG_MATERIAL_GLOSSY;
    for (int i = 0; i < 3; i++) {
        m->diffuse[i] = 0.0f;
        m->specular[i] = 0.5f;
    }
    m->exponent = 10.0f;
    SgRenderOptions o;
    openpgl_options(&o, s, mode, SG_ROULETTE_ALBEDO);
    o.seed = 2;
    Estimate e = estimate(s, &o, 24);
    sgt_scene_free(s);
    cr_log_info("glossy furnace, openpgl %s: guide drew %.3f", sg_openpgl_mode_name(mode), e.lobe_share);
    cr_assert_eq(e.nonfinite, 0);
    return e.lobe_share;
}

Test(render_openpgl, ris_guides_glossy_vertices, .timeout = 300)
{
    skip_without_openpgl();
    double ris = glossy_furnace_share(SG_OPENPGL_RIS), mis = glossy_furnace_share(SG_OPENPGL_MIS);
    /* RIS keeps the guide's candidate about as often as the BSDF's once trained */
    cr_assert_gt(ris, 0.1, "RIS: the guide drew %.3f of the glossy bounces", ris);
    cr_assert_eq(mis, 0.0, "MIS: the guide drew %.3f of the glossy bounces (Cycles never guides them)", mis);
}

/* ---- a field remembers the mode it was trained by ---- */

Test(render_openpgl, field_of_one_mode_is_refused_by_the_other, .timeout = 300)
{
    skip_without_openpgl();
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o;
    openpgl_options(&o, s, SG_OPENPGL_MIS, SG_ROULETTE_LEARNED);
    o.training_passes = 2;
    char path[] = "/tmp/sg-test-openpgl-field-XXXXXX";
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    close(fd);
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    cr_assert(sg_renderer_train(r, &err), "%s", err.message);
    cr_assert(sg_renderer_write_field(r, path, &err), "%s", err.message);
    sg_renderer_free(r);

    SgRenderOptions same = o, other = o;
    other.openpgl_mode = SG_OPENPGL_RIS;
    r = sg_renderer_create(s, &same, &err);
    cr_assert_not_null(r, "%s", err.message);
    cr_assert(sg_renderer_read_field(r, path, &err), "the mis field for a mis render: %s", err.message);
    sg_renderer_free(r);
    r = sg_renderer_create(s, &other, &err);
    cr_assert_not_null(r, "%s", err.message);
    SgError refused = {0};
    bool read = sg_renderer_read_field(r, path, &refused);
    sg_renderer_free(r);
    unlink(path);
    sgt_scene_free(s);
    cr_assert_not(read, "a mis field was taken for a ris render");
    cr_assert(strstr(refused.message, "openpgl mis") != NULL, "the refusal names the mode: %s", refused.message);
}

/* ---- the training's schedule: Cycles' (1, 2, then 4 passes per update) ---- */

Test(render_openpgl, training_updates_on_cycles_schedule, .timeout = 300)
{
    skip_without_openpgl();
    SgScene *s = sgt_furnace_scene();
    SgRenderOptions o;
    openpgl_options(&o, s, SG_OPENPGL_MIS, SG_ROULETTE_ALBEDO);
    o.training_passes = 9; /* updates after passes 1, 3 and 7, and at the end: 4 */
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, &o, &err);
    cr_assert_not_null(r, "%s", err.message);
    cr_assert(sg_renderer_train(r, &err), "%s", err.message);
    SgRenderStats stats = sgt_stats(r);
    sg_renderer_free(r);
    sgt_scene_free(s);
    cr_assert_eq(stats.training_passes, 9, "every training pass's paths reach the field: %d", stats.training_passes);
    cr_assert_eq(stats.training_updates, 4, "the schedule: %d updates", stats.training_updates);
    cr_assert_eq(SG_OPENPGL_TRAINING_PASSES, 1 + 2 + 4 * 126, "Cycles' 128 updates");
}
