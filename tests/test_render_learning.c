/* The guided mode's learned mixture weight (render/guides/mixture_learning.h):
 * which candidate the second-moment estimates pick on synthetic bounces,
 * the coarse regions answering for sparse fine ones, and, in a rendered
 * two-room scene, that learning keeps the good of a good guide and drops a
 * bad one (the variance of the image against BSDF sampling). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../render/guides/mixture_learning.h"
#include "../render/renderer.h"
#include "../render/sampling.h"
#include "rng.h"
#include "support_render.h"

static SgMixtureLearner *unit_learner_from(int initial)
{
    SgError err = {0};
    /* 8 fine cells a side over the unit cube, 2 tiles */
    SgMixtureLearner *l = sg_mixture_learner_create(v3(0, 0, 0), v3(1, 1, 1), 8, 2, initial, &err);
    cr_assert_not_null(l, "%s", err.message);
    return l;
}

static SgMixtureLearner *unit_learner(void) { return unit_learner_from(0); }

/* Bounces drawn by BSDF sampling (alpha 1, p = pdf_bsdf) in one region: a
 * share `lit` of them land in a small bright cone carrying value
 * f cos L = g, at cosine `cos_light` from the lobe's axis; the others miss
 * it at cosine 0.3. */
static void feed_records(SgMixtureLearner *l, uint32_t region, int count, double lit, float cos_light, uint64_t seed)
{
    SgRng rng;
    sg_rng_seed(&rng, seed, 7);
    const float pdf_bsdf = 0.3f, g = 2.0f;
    for (int i = 0; i < count; i++) {
        bool hit = sg_rng_float(&rng) < lit;
        SgMixtureRecord rec = {.region = region,
                               .radiance = -1.0f,
                               .lobe = true,
                               .pdf_bsdf = pdf_bsdf,
                               .cos_axis = hit ? cos_light : 0.3f,
                               .pdf = pdf_bsdf,
                               .estimate = hit ? g / pdf_bsdf : 0.0f,
                               .weight = 1.0f};
        sg_mixture_record(l, (uint32_t)(i & 1), &rec);
    }
}

/* The region of a point on a floor (normal +y). */
static uint32_t floor_region(const SgMixtureLearner *l, float x, float y, float z)
{
    return sg_mixture_region(l, v3(x, y, z), v3(0, 1, 0));
}

/* The same, learned at once. */
static void feed(SgMixtureLearner *l, uint32_t region, int count, double lit, float cos_light, uint64_t seed)
{
    feed_records(l, region, count, lit, cos_light, seed);
    sg_mixture_update(l);
}

/* The renderer's split update: a pass's records are learned while the next
 * pass renders and reach the view (what bounces read) only when that pass
 * ends, so that the view never changes during a pass. */
Test(render_learning, learned_choices_reach_the_view_between_passes)
{
    SgMixtureLearner *l = unit_learner();
    const Vec3 p = v3(0.3f, 0.3f, 0.3f), n = v3(0, 1, 0);
    const SgMixtureView *view = sg_mixture_view(l);
    uint32_t r = sg_mixture_region(l, p, n);
    SgMixtureCandidate seen;
    bool learning;
    feed_records(l, r, 4000, 0.05, 0.995f, 1); /* pass 1 renders */
    sg_mixture_end_pass(l);
    sg_mixture_learn(l); /* during pass 2 */
    sg_mixture_lookup(view, p, sg_mixture_normal_bin(n), &seen, &learning);
    cr_assert_float_eq(seen.alpha, 1.0f, 0.0f, "the view changed during a pass");
    SgMixtureCandidate c = sg_mixture_choice(l, r);
    cr_assert(c.alpha == 0.6f && c.exponent == 64.0f, "learned: alpha %g exponent %g", c.alpha, c.exponent);
    sg_mixture_end_pass(l); /* pass 2 ends */
    sg_mixture_lookup(view, p, sg_mixture_normal_bin(n), &seen, &learning);
    cr_assert(seen.alpha == 0.6f && seen.exponent == 64.0f, "view after the pass: alpha %g exponent %g", seen.alpha,
              seen.exponent);
    /* records left unlearned are learned when the next pass ends, not lost */
    feed_records(l, r, 1000, 0.05, 0.995f, 2);
    sg_mixture_end_pass(l);
    sg_mixture_end_pass(l);
    cr_assert_eq(sg_mixture_region_samples(l, r), 5000);
    sg_mixture_learner_free(l);
}

Test(render_learning, the_lobe_wins_where_the_light_comes_along_the_guide)
{
    SgMixtureLearner *l = unit_learner();
    uint32_t r = floor_region(l, 0.3f, 0.3f, 0.3f);
    cr_assert_neq(r, SG_NO_REGION);
    cr_assert_float_eq(sg_mixture_choice(l, r).alpha, 1.0f, 0.0f); /* nothing learned yet */
    feed(l, r, 4000, 0.05, 0.995f, 1);
    /* the light right on the axis: the narrowest lobe with the most weight wins
     * (its density there is 75x the BSDF's) */
    SgMixtureCandidate c = sg_mixture_choice(l, r);
    cr_assert(c.alpha == 0.6f && c.exponent == 64.0f, "alpha %g exponent %g", c.alpha, c.exponent);
    cr_assert_eq(sg_mixture_region_samples(l, r), 4000);
    sg_mixture_learner_free(l);
}

Test(render_learning, the_bsdf_wins_where_the_guide_points_away)
{
    SgMixtureLearner *l = unit_learner();
    uint32_t r = sg_mixture_region(l, v3(0.7f, 0.3f, 0.3f), v3(0, 0, -1));
    feed(l, r, 4000, 0.3, 0.0f, 2);
    cr_assert_float_eq(sg_mixture_choice(l, r).alpha, 1.0f, 0.0f, "alpha %g", sg_mixture_choice(l, r).alpha);
    sg_mixture_learner_free(l);
}

Test(render_learning, a_small_gain_does_not_pay_for_the_guide)
{
    /* the lobe's wide version only slightly denser on the light than the
     * BSDF (1.4x at cosine 0.85 for exponent 4, less for the others): the
     * variance falls by less than guiding costs, so the BSDF stays */
    SgMixtureLearner *l = unit_learner();
    uint32_t r = sg_mixture_region(l, v3(0.3f, 0.7f, 0.3f), v3(1, 0, 0));
    feed(l, r, 20000, 0.3, 0.85f, 3);
    cr_assert_float_eq(sg_mixture_choice(l, r).alpha, 1.0f, 0.0f, "alpha %g", sg_mixture_choice(l, r).alpha);
    sg_mixture_learner_free(l);
}

/* Sky samples at a region's vertices, drawn with the default share: a
 * window of 0.05 sr where the portal density is 20 and the sky's own 1/(4 pi)
 * (a constant sky). `inside`: the vertex is in a room that sees the sky
 * only through the window (what the sky's own sampling sends elsewhere
 * meets a wall); else it stands outside, under the whole sky, and the
 * window leads into the house (a sample through it is blocked). */
static void feed_sky(SgMixtureLearner *l, uint32_t region, int count, bool inside, uint64_t seed)
{
    SgRng rng;
    sg_rng_seed(&rng, seed, 9);
    const float share = 0.8f, portal = 20.0f, sky = 1.0f / (4.0f * 3.14159265f), window = 0.05f;
    for (int i = 0; i < count; i++) {
        bool through = sg_rng_float(&rng) < share || sg_rng_float(&rng) < sky * window;
        bool lit = inside ? through : !through;
        SgMixtureRecord rec = {.region = region, .radiance = -1.0f, .sky = true,
                               .sky_contribution = lit ? 1.0f : 0.0f, .sky_pdf_portals = through ? portal : 0.0f,
                               .sky_pdf_sky = sky, .sky_share = share};
        sg_mixture_record(l, (uint32_t)(i & 1), &rec);
    }
}

/* Each region learns how many of its sky samples go through the portals:
 * nearly all in a room lit through its window, none out in the open;
 * regions without sky samples keep the default until their coarse region
 * or the scene has chosen, and the choice survives a field file. */
Test(render_learning, regions_learn_their_share_of_sky_samples_through_the_portals)
{
    SgMixtureLearner *l = unit_learner();
    uint32_t room = floor_region(l, 0.1f, 0.1f, 0.1f);
    uint32_t open = floor_region(l, 0.9f, 0.9f, 0.9f);
    uint32_t near_room = floor_region(l, 0.2f, 0.1f, 0.1f);
    const SgMixtureView *view = sg_mixture_view(l);
    cr_assert_eq(sg_portal_shares[SG_PORTAL_SHARE_DEFAULT], 0.8f, "the default is render/lights.h's PORTAL_SHARE");
    cr_assert_eq(sg_mixture_portal_share(view, room), 0.8f);
    cr_assert_eq(sg_mixture_portal_share(view, SG_NO_REGION), 0.8f);
    feed_sky(l, room, 4000, true, 1);
    feed_sky(l, open, 4000, false, 2);
    sg_mixture_update(l);
    cr_assert_eq(sg_mixture_portal_share(view, room), 0.99f, "in the room: %g", sg_mixture_portal_share(view, room));
    cr_assert_eq(sg_mixture_portal_share(view, open), 0.0f, "outside: %g", sg_mixture_portal_share(view, open));
    /* a region with no sky samples of its own: its coarse region's (the room's) */
    cr_assert_eq(sg_mixture_portal_share(view, near_room), 0.99f, "beside the room: %g",
                 sg_mixture_portal_share(view, near_room));
    double use[SG_PORTAL_SHARES];
    cr_assert(sg_mixture_portal_share_use(l, use));
    /* of the samples that brought light: the room's 80% through the window, the open's 20% beside it */
    cr_assert_float_eq(use[0] + use[SG_PORTAL_SHARES - 1], 1.0, 1e-12);
    cr_assert(use[SG_PORTAL_SHARES - 1] > 0.75 && use[SG_PORTAL_SHARES - 1] < 0.85, "%g", use[SG_PORTAL_SHARES - 1]);

    /* a field file's bytes give a new learner the same shares */
    size_t size = sg_mixture_view_size(l);
    unsigned char *bytes = malloc(size);
    sg_mixture_view_save(l, bytes);
    SgMixtureLearner *loaded = unit_learner();
    cr_assert(sg_mixture_view_restore(loaded, bytes, size));
    const SgMixtureView *lv = sg_mixture_view(loaded);
    cr_assert_eq(sg_mixture_portal_share(lv, room), 0.99f);
    cr_assert_eq(sg_mixture_portal_share(lv, open), 0.0f);
    /* a share index out of range is refused */
    uint32_t regions; /* the shares follow the count, the scene's radiance and 33 bytes a region */
    memcpy(&regions, bytes, sizeof regions);
    bytes[sizeof(uint32_t) + sizeof(float) + (size_t)regions * (1 + 8 * sizeof(float)) + room] = SG_PORTAL_SHARES;
    cr_assert_not(sg_mixture_view_restore(loaded, bytes, size));
    free(bytes);
    sg_mixture_learner_free(loaded);
    sg_mixture_learner_free(l);
}

Test(render_learning, sparse_regions_take_their_coarse_region_s_choice)
{
    /* before anything is learned: a mixture (so that `far` below keeps to
     * the BSDF only by following the whole scene's choice) */
    SgMixtureLearner *l = unit_learner_from(SG_MIXTURE_INITIAL);
    uint32_t far = floor_region(l, 0.9f, 0.1f, 0.1f);
    cr_assert_lt(sg_mixture_choice(l, far).alpha, 1.0f);
    /* fine cells are 1/8; coarse ones 4 fine cells: (0.05..0.45) share one */
    uint32_t busy = floor_region(l, 0.05f, 0.05f, 0.05f);
    uint32_t sparse = floor_region(l, 0.4f, 0.4f, 0.4f);
    uint32_t other_side = sg_mixture_region(l, v3(0.4f, 0.4f, 0.4f), v3(0, -1, 0));
    uint32_t away = floor_region(l, 0.6f, 0.6f, 0.6f);
    cr_assert(busy != sparse && sparse != other_side && far != sparse && away != far);
    /* the lobe wins at `busy`; the BSDF wins at `away` (another coarse
     * cell), where bounces bring back more light in all: the scene as a
     * whole keeps to the BSDF */
    feed(l, busy, 4000, 0.05, 0.995f, 4);
    feed(l, away, 4000, 0.6, 0.0f, 5);
    feed(l, sparse, 10, 0.05, 0.995f, 6);
    float lobe = sg_mixture_candidates[SG_MIXTURE_SKELETON_CANDIDATES - 1].alpha;
    cr_assert_float_eq(sg_mixture_choice(l, busy).alpha, lobe, 0.0f);
    cr_assert_float_eq(sg_mixture_choice(l, away).alpha, 1.0f, 0.0f);
    cr_assert_float_eq(sg_mixture_choice(l, sparse).alpha, lobe, 0.0f, "sparse region: %g",
                       sg_mixture_choice(l, sparse).alpha);
    /* a region with no samples at all in the same coarse cell also follows it */
    uint32_t empty = floor_region(l, 0.3f, 0.1f, 0.2f);
    cr_assert_eq(sg_mixture_region_samples(l, empty), 0);
    cr_assert_float_eq(sg_mixture_choice(l, empty).alpha, lobe, 0.0f);
    /* the other side of a wall and a coarse cell with no samples follow the
     * whole scene's choice */
    cr_assert_float_eq(sg_mixture_choice(l, other_side).alpha, 1.0f, 0.0f);
    cr_assert_float_eq(sg_mixture_choice(l, far).alpha, 1.0f, 0.0f);
    /* and the inline view agrees with the functions */
    SgMixtureCandidate a;
    bool learning;
    uint32_t r = sg_mixture_lookup(sg_mixture_view(l), v3(0.4f, 0.4f, 0.4f), sg_mixture_normal_bin(v3(0, 1, 0)), &a, &learning);
    cr_assert_eq(r, sparse);
    cr_assert_float_eq(a.alpha, lobe, 0.0f);
    cr_assert(learning);
    /* outside the grid (only rounding puts a hit point there) or NaN: the nearest cell */
    r = sg_mixture_lookup(sg_mixture_view(l), v3(2, 0.5f, 0.5f), sg_mixture_normal_bin(v3(0, 1, 0)), &a, &learning);
    cr_assert_eq(r, floor_region(l, 1.0f, 0.5f, 0.5f));
    r = sg_mixture_lookup(sg_mixture_view(l), v3(NAN, -5.0f, 0.0f), sg_mixture_normal_bin(v3(0, 1, 0)), &a, &learning);
    cr_assert_eq(r, floor_region(l, 0.0f, 0.0f, 0.0f));
    sg_mixture_learner_free(l);
}

Test(render_learning, a_region_with_enough_samples_settles)
{
    SgMixtureLearner *l = unit_learner();
    uint32_t r = floor_region(l, 0.3f, 0.3f, 0.3f);
    cr_assert(sg_mixture_learning(l, r));
    feed(l, r, SG_MIXTURE_SETTLED_SAMPLES - 1000, 0.05, 0.995f, 6);
    cr_assert(sg_mixture_learning(l, r), "settled before its records reached SG_MIXTURE_SETTLED_SAMPLES");
    feed(l, r, 2000, 0.05, 0.995f, 7);
    cr_assert_not(sg_mixture_learning(l, r));
    sg_mixture_learner_free(l);
}

/* Vertices that report only what left them (no guided bounce): `count`
 * records, every `period`-th from the first carrying radiance `rare`, the
 * others `usual` (period 2: alternating), from two threads in turn. */
static void feed_radiance(SgMixtureLearner *l, uint32_t region, int count, int period, float rare, float usual)
{
    for (int i = 0; i < count; i++) {
        SgMixtureRecord rec = {.region = region, .radiance = i % period == 0 ? rare : usual, .weight = 1.0f};
        sg_mixture_record(l, (uint32_t)(i & 1), &rec);
    }
    sg_mixture_update(l);
}

Test(render_learning, regions_learn_the_second_moment_of_what_leaves_them)
{
    SgMixtureLearner *l = unit_learner();
    const SgMixtureView *v = sg_mixture_view(l);
    uint32_t lit = floor_region(l, 0.05f, 0.05f, 0.05f);
    uint32_t sparse = floor_region(l, 0.4f, 0.4f, 0.4f);
    uint32_t dark = floor_region(l, 0.9f, 0.9f, 0.9f);
    uint32_t elsewhere = sg_mixture_region(l, v3(0.9f, 0.1f, 0.9f), v3(1, 0, 0));
    cr_assert_lt(sg_mixture_radiance(v, lit), 0.0f, "nothing known yet");
    feed_radiance(l, lit, 1000, 2, 1.0f, 3.0f);
    feed_radiance(l, dark, 1000, 2, 0.0f, 0.1f);
    feed_radiance(l, sparse, 10, 2, 50.0f, 50.0f);
    /* root mean square: sqrt((1 + 9) / 2), not the mean 2 */
    float got = sg_mixture_radiance(v, lit);
    cr_assert_float_eq(got, sqrtf(5.0f), 1e-5f, "lit: %g", got);
    got = sg_mixture_radiance(v, dark);
    cr_assert_float_eq(got, sqrtf(0.005f), 1e-6f, "dark: %g", got);
    /* too few of its own: its coarse region's (the lit region's 1000 and its 10) */
    float coarse = sqrtf((500.0f * 1.0f + 500.0f * 9.0f + 10.0f * 2500.0f) / 1010.0f);
    got = sg_mixture_radiance(v, sparse);
    cr_assert_float_eq(got, coarse, 1e-4f, "sparse: %g vs %g", got, coarse);
    /* none in its coarse region: the whole scene's */
    float global = sqrtf((500.0f * 1.0f + 500.0f * 9.0f + 500.0f * 0.01f + 10.0f * 2500.0f) / 2010.0f);
    got = sg_mixture_radiance(v, elsewhere);
    cr_assert_float_eq(got, global, 1e-4f, "elsewhere: %g vs %g", got, global);
    /* vertices without a guided bounce teach nothing about the mixture */
    cr_assert_eq(sg_mixture_region_samples(l, lit), 0);
    cr_assert_float_eq(sg_mixture_choice(l, lit).alpha, 1.0f, 0.0f);
    sg_mixture_learner_free(l);
}

/* What leaves a vertex in the dark is heavy-tailed: one report in 100
 * carries 10, the rest nothing (mean square 1). A region that has seen 200
 * of them and none of the rare ones (13% of such regions) must not claim a
 * mean square of 0: the learned roulette would cut its paths at its floor
 * and the rare survivor that finds the light would come back 20 times too
 * heavy (the dark corridor's fireflies). Its coarse region, which saw 3000 of the
 * same paths next door, pulls it up as MIN_SAMPLES (256) reports would. */
Test(render_learning, a_region_that_missed_the_rare_light_is_not_taken_for_dark)
{
    SgMixtureLearner *l = unit_learner();
    /* one coarse cell (fine cells 1/8, coarse ones 4 of them) */
    uint32_t busy = floor_region(l, 0.05f, 0.05f, 0.05f);
    uint32_t unlucky = floor_region(l, 0.3f, 0.3f, 0.3f);
    cr_assert_neq(busy, unlucky);
    feed_radiance(l, busy, 3000, 100, 10.0f, 0.0f);
    feed_radiance(l, unlucky, 200, 2, 0.0f, 0.0f);
    double coarse_m2 = 30.0 * 100.0 / 3200.0; /* busy's 3000 and unlucky's 200 */
    float want = (float)sqrt(256.0 * coarse_m2 / (200.0 + 256.0));
    const SgMixtureView *v = sg_mixture_view(l);
    float got = sg_mixture_radiance(v, unlucky);
    cr_log_info("unlucky region: rms %g (its coarse region's %g, its own 0)", got, sqrt(coarse_m2));
    cr_assert_float_eq(got, want, 1e-4f, "unlucky region: rms %g, want %g", got, want);
    /* the busy region's own 3000 reports rule its estimate (their M2 is 1) */
    got = sg_mixture_radiance(v, busy);
    cr_assert_float_eq(got, 1.0f, 1e-4f, "busy region: rms %g", got);
    sg_mixture_learner_free(l);
}

/* ---- the learned axis ------------------------------------------------------ */

/* A pass of `count` bounces drawn by BSDF sampling (cosine about n, albedo
 * 1, so v = L) in one region: light L = 20 in a cone of cosine 0.97 about
 * `light`, `ambient` elsewhere; the skeleton's axis is `skeleton`. */
static void feed_directions(SgMixtureLearner *l, uint32_t region, Vec3 n, Vec3 light, Vec3 skeleton, float ambient,
                            int count, SgRng *rng)
{
    for (int i = 0; i < count; i++) {
        Vec3 d = sg_sample_cosine_hemisphere(n, sg_rng_float(rng), sg_rng_float(rng));
        float p = fmaxf(v3_dot(d, n), 1e-6f) / 3.14159265f;
        float c = v3_dot(d, skeleton);
        SgMixtureRecord rec = {.region = region,
                               .radiance = -1.0f,
                               .lobe = true,
                               .pdf_bsdf = p,
                               .pdf = p,
                               .cos_axis = c,
                               .cos_mirror = c - 2.0f * v3_dot(skeleton, n) * v3_dot(d, n),
                               .direction = d,
                               .normal = n,
                               .estimate = v3_dot(d, light) > 0.97f ? 20.0f : ambient,
                               .weight = 1.0f};
        sg_mixture_record(l, (uint32_t)(i & 1), &rec);
    }
}

/* The light comes from the side the skeleton does not point to: the
 * region learns the light's direction as its axis and draws its lobe
 * around it, where the skeleton's candidates would lose to the BSDF. */
Test(render_learning, a_region_learns_the_axis_the_skeleton_missed)
{
    SgMixtureLearner *l = unit_learner();
    const Vec3 n = v3(0, 1, 0), light = v3_normalize(v3(1, 1, 0)), skeleton = v3_normalize(v3(-1, 1, 0.3f));
    uint32_t r = sg_mixture_region(l, v3(0.3f, 0.3f, 0.3f), n);
    SgRng rng;
    sg_rng_seed(&rng, 11, 3);
    Vec3 axis;
    cr_assert_not(sg_mixture_region_axis(l, r, &axis), "no axis before any record");
    for (int pass = 0; pass < 8; pass++) {
        feed_directions(l, r, n, light, skeleton, 0.0f, 400, &rng);
        sg_mixture_end_pass(l);
    }
    cr_assert(sg_mixture_region_axis(l, r, &axis));
    float angle = acosf(fminf(v3_dot(axis, light), 1.0f)) * 57.2958f;
    cr_log_info("learned axis %g %g %g: %.2f degrees from the light", axis.x, axis.y, axis.z, angle);
    cr_assert_lt(angle, 3.0f, "the axis is %.2f degrees from the light", angle);
    SgMixtureCandidate c = sg_mixture_choice(l, r);
    cr_assert(c.learned_axis && c.alpha < 1.0f && c.exponent == 64.0f, "choice: alpha %g exponent %g, %s axis",
              c.alpha, c.exponent, c.learned_axis ? "learned" : "skeleton");
    cr_assert(sg_mixture_view(l)->state[r] & SG_MIXTURE_STATE_AXIS);
    cr_assert_not(sg_mixture_view(l)->state[r] & SG_MIXTURE_STATE_LOBE, "no cache query for a learned axis");
    cr_assert_gt(sg_mixture_learned_axis_fraction(l), 0.99);
    sg_mixture_learner_free(l);
}

/* A learned axis is judged only on bounces drawn while it was in use. As
 * the renderer runs it, a pass's records are learned during the next pass
 * (sg_mixture_learn beside it) and what that learned reaches the view when
 * that pass ends: a refit made from pass 2's records is in use from pass 4
 * on, and pass 3's records, drawn around the old axis, must not
 * judge the new one (here they would favour it: they would make it win
 * before any bounce was drawn around it). */
Test(render_learning, a_new_axis_is_judged_on_the_passes_that_use_it)
{
    SgMixtureLearner *l = unit_learner();
    const Vec3 n = v3(0, 0, 1), light = v3_normalize(v3(0, -1, 2)), skeleton = v3_normalize(v3(1, 0, 0.2f));
    uint32_t r = sg_mixture_region(l, v3(0.6f, 0.6f, 0.6f), n);
    SgRng rng;
    sg_rng_seed(&rng, 12, 3);
    feed_directions(l, r, n, light, skeleton, 0.0f, 1000, &rng); /* pass 1 */
    sg_mixture_end_pass(l);
    sg_mixture_learn(l); /* during pass 2: the first axis, in use from pass 3 */
    feed_directions(l, r, n, light, skeleton, 0.0f, 3000, &rng); /* pass 2 */
    sg_mixture_end_pass(l);
    Vec3 first, second;
    cr_assert(sg_mixture_region_axis(l, r, &first), "fitted and published");
    sg_mixture_learn(l); /* during pass 3: 4000 records, the axis is refitted */
    feed_directions(l, r, n, light, skeleton, 0.0f, 600, &rng); /* pass 3, around the first axis */
    sg_mixture_end_pass(l);
    cr_assert(sg_mixture_region_axis(l, r, &second));
    cr_assert(first.x != second.x || first.y != second.y || first.z != second.z, "refitted");
    sg_mixture_learn(l); /* during pass 4: pass 3's records */
    cr_assert_not(sg_mixture_choice(l, r).learned_axis, "judged on bounces drawn around the old axis");
    feed_directions(l, r, n, light, skeleton, 0.0f, 600, &rng); /* pass 4, around the new axis */
    sg_mixture_end_pass(l);
    sg_mixture_learn(l);
    cr_assert(sg_mixture_choice(l, r).learned_axis, "alpha %g", sg_mixture_choice(l, r).alpha);
    sg_mixture_learner_free(l);
}

/* A small bright patch near the region: its direction changes across the
 * region (parallax), so one learned direction blurs it, while the mean of
 * where the bright bounces ended finds the patch, and a narrow lobe toward
 * it from each vertex wins. */
Test(render_learning, a_region_learns_where_a_near_light_lies)
{
    SgMixtureLearner *l = unit_learner();
    const Vec3 n = v3(0, 1, 0), corner = v3(0.25f, 0.25f, 0.25f), patch = v3(0.3125f, 0.4f, 0.3125f);
    uint32_t r = sg_mixture_region(l, v3(0.3f, 0.3f, 0.3f), n);
    SgRng rng;
    sg_rng_seed(&rng, 14, 3);
    for (int pass = 0; pass < 10; pass++) {
        for (int i = 0; i < 400; i++) {
            /* a vertex anywhere on the region's floor (fine cells are 1/8) */
            Vec3 x = v3(corner.x + 0.125f * sg_rng_float(&rng), 0.25f, corner.z + 0.125f * sg_rng_float(&rng));
            cr_assert_eq(sg_mixture_region(l, x, n), r);
            Vec3 d = sg_sample_cosine_hemisphere(n, sg_rng_float(&rng), sg_rng_float(&rng));
            Vec3 to = v3_sub(patch, x);
            float dist = sqrtf(v3_dot(to, to));
            bool hit = v3_dot(d, v3_scale(to, 1.0f / dist)) > 0.995f;
            float p = fmaxf(v3_dot(d, n), 1e-6f) / 3.14159265f;
            SgMixtureRecord rec = {.region = r, .radiance = -1.0f, .lobe = true, .no_skeleton = true,
                                   .pdf_bsdf = p, .pdf = p, .direction = d, .normal = n, .position = x,
                                   .distance = hit ? dist : 1.0f, .estimate = hit ? 20.0f : 0.0f, .weight = 1.0f};
            sg_mixture_record(l, (uint32_t)(i & 1), &rec);
        }
        sg_mixture_end_pass(l);
    }
    Vec3 point;
    cr_assert(sg_mixture_region_point(l, r, &point));
    Vec3 off = v3_sub(point, patch);
    float miss = sqrtf(v3_dot(off, off));
    cr_log_info("learned point %g %g %g, %.4f from the patch", point.x, point.y, point.z, miss);
    cr_assert_lt(miss, 0.01f, "the learned point is %.4f from the patch", miss);
    SgMixtureCandidate c = sg_mixture_choice(l, r);
    cr_assert(c.learned_point && c.exponent == 64.0f, "choice: alpha %g exponent %g, %s", c.alpha, c.exponent,
              c.learned_point ? "toward the point" : c.learned_axis ? "around the direction" : "skeleton or BSDF");
    sg_mixture_learner_free(l);
}

/* Light from two lit patches on either side: the mean direction of what
 * came back lies between them and misses both, so no lobe about it helps;
 * the region's histogram of directions has both peaks, and its candidate
 * wins (and draws without a cache query). */
Test(render_learning, a_region_lit_from_two_sides_learns_both)
{
    SgMixtureLearner *l = unit_learner();
    const Vec3 n = v3(0, 1, 0), left = v3_normalize(v3(-1, 1, 0.2f)), right = v3_normalize(v3(1, 0.8f, -0.3f));
    const Vec3 skeleton = v3_normalize(v3(0, 1, 1)), unlit = v3_normalize(v3(0, 0.6f, -1));
    uint32_t r = sg_mixture_region(l, v3(0.55f, 0.3f, 0.3f), n);
    SgRng rng;
    sg_rng_seed(&rng, 15, 3);
    for (int pass = 0; pass < 12; pass++) {
        for (int i = 0; i < 600; i++) {
            Vec3 d = sg_sample_cosine_hemisphere(n, sg_rng_float(&rng), sg_rng_float(&rng));
            float p = fmaxf(v3_dot(d, n), 1e-6f) / 3.14159265f, c = v3_dot(d, skeleton);
            bool lit = v3_dot(d, left) > 0.97f || v3_dot(d, right) > 0.97f;
            SgMixtureRecord rec = {.region = r, .radiance = -1.0f, .lobe = true, .pdf_bsdf = p, .pdf = p,
                                   .cos_axis = c, .cos_mirror = c - 2.0f * v3_dot(skeleton, n) * v3_dot(d, n),
                                   .direction = d, .normal = n, .estimate = lit ? 20.0f : 0.0f, .weight = 1.0f};
            sg_mixture_record(l, (uint32_t)(i & 1), &rec);
        }
        sg_mixture_end_pass(l);
    }
    Vec3 axis;
    cr_assert(sg_mixture_region_axis(l, r, &axis));
    cr_log_info("learned axis %.2f %.2f %.2f", axis.x, axis.y, axis.z);
    cr_assert_lt(fmaxf(v3_dot(axis, left), v3_dot(axis, right)), 0.9f, "the mean direction misses both");
    const SgMixtureView *v = sg_mixture_view(l);
    cr_assert_neq(v->histogram_of[r], SG_NO_REGION, "a histogram");
    const float *cdf = &v->histogram[(size_t)v->histogram_of[r] * SG_MIXTURE_BINS];
    float uniform = 1.0f / (4.0f * 3.14159265f);
    float at_left = sg_mixture_histogram_pdf(cdf, left), at_right = sg_mixture_histogram_pdf(cdf, right);
    float at_unlit = sg_mixture_histogram_pdf(cdf, unlit);
    cr_log_info("histogram density over uniform: left %.1f, right %.1f, unlit %.2f", at_left / uniform,
                at_right / uniform, at_unlit / uniform);
    cr_assert(at_left > 10.0f * uniform && at_right > 10.0f * uniform, "both peaks: %g, %g", at_left / uniform,
              at_right / uniform);
    cr_assert_lt(at_unlit, 0.2f * uniform, "no light from %g", at_unlit / uniform);
    SgMixtureCandidate c = sg_mixture_choice(l, r);
    cr_assert(c.learned_histogram && c.alpha < 1.0f, "choice: alpha %g exponent %g, %s", c.alpha, c.exponent,
              c.learned_histogram ? "histogram" : c.learned_axis ? "learned lobe" : "skeleton or BSDF");
    cr_assert(v->state[r] & SG_MIXTURE_STATE_AXIS, "no cache query");
    sg_mixture_learner_free(l);
}

/* Light from everywhere alike: BSDF sampling has no variance, any lobe
 * adds some, so the region keeps to the BSDF though it has an axis. (The
 * bright cone is below the surface, where no bounce goes: one at grazing,
 * half above the surface, is light from one side, which the learned
 * histogram rightly draws.) */
Test(render_learning, a_learned_axis_does_not_win_where_light_is_even)
{
    SgMixtureLearner *l = unit_learner();
    const Vec3 n = v3(1, 0, 0);
    uint32_t r = sg_mixture_region(l, v3(0.3f, 0.6f, 0.3f), n);
    SgRng rng;
    sg_rng_seed(&rng, 13, 3);
    for (int pass = 0; pass < 8; pass++) {
        feed_directions(l, r, n, v3(-1, 0, 0), v3(0, 1, 0), 1.0f, 400, &rng);
        sg_mixture_end_pass(l);
    }
    Vec3 axis;
    cr_assert(sg_mixture_region_axis(l, r, &axis));
    cr_assert_float_eq(sg_mixture_choice(l, r).alpha, 1.0f, 0.0f, "alpha %g", sg_mixture_choice(l, r).alpha);
    sg_mixture_learner_free(l);
}

/* ---- rendered: two rooms and a window (sgt_window_rooms) ------------------ */

typedef struct PassStats {
    double mean;     /* of the image, over the passes counted */
    double rays;     /* traced per pass counted */
} PassStats;

/* Mean over the image of the per-pixel variance of the samples, from the
 * passes after `skip` (learning has had its first passes by then). */
static double pixel_variance(SgScene *s, SgRenderOptions *o, int skip, int passes, PassStats *ps)
{
    SgError err = {0};
    SgRenderer *r = sg_renderer_create(s, o, &err);
    cr_assert_not_null(r, "%s", err.message);
    size_t n = (size_t)o->width * o->height;
    double *sum = calloc(n, sizeof *sum), *sum2 = calloc(n, sizeof *sum2);
    uint64_t rays_before = 0;
    for (int p = 0; p < skip + passes; p++) {
        if (p == skip)
            rays_before = sgt_stats(r).rays;
        sg_renderer_pass(r);
        if (p < skip)
            continue;
        const float *last = sg_renderer_last_pass(r);
        for (size_t i = 0; i < n; i++) {
            double v = last[3 * i];
            sum[i] += v;
            sum2[i] += v * v;
        }
    }
    cr_assert_eq(sgt_stats(r).nonfinite, 0);
    double var = 0.0, mean = 0.0;
    for (size_t i = 0; i < n; i++) {
        double m = sum[i] / passes;
        var += (sum2[i] / passes - m * m) * passes / (passes - 1);
        mean += m;
    }
    if (ps) {
        ps->mean = mean / n;
        ps->rays = (double)(sgt_stats(r).rays - rays_before) / passes;
    }
    free(sum);
    free(sum2);
    sg_renderer_free(r);
    return var / n;
}

/* A render of the two rooms with the guide pointing at `guide_point`. */
typedef struct WindowRun {
    SgSampling mode;
    float alpha;
    SgRoulette roulette;
    int max_depth;
    uint64_t seed;
    int passes; /* counted, after 8 */
} WindowRun;

static double window_variance(WindowRun run, const double guide_point[3], PassStats *ps)
{
    SgScene *s = sgt_window_rooms();
    SgRenderOptions o;
    sg_render_options_default(&o, s);
    SgtFixedPoint fp;
    memcpy(fp.point, guide_point, sizeof fp.point);
    o.importance.importance_point = sgt_fixed_point_guide;
    o.importance.ctx = &fp;
    o.sampling = run.mode;
    o.alpha = run.alpha;
    o.roulette = run.roulette;
    o.max_depth = run.max_depth;
    o.seed = run.seed;
    double v = pixel_variance(s, &o, 8, run.passes, ps);
    sgt_scene_free(s);
    return v;
}

static double variance_with(SgSampling mode, float alpha, const double guide_point[3])
{
    /* albedo roulette: the mixture alone */
    return window_variance((WindowRun){mode, alpha, SG_ROULETTE_ALBEDO, 8, 11, 96}, guide_point, NULL);
}

Test(render_learning, learning_keeps_a_good_guide_and_drops_a_bad_one, .timeout = 120)
{
    const double door[3] = {2.0, 1.0, 1.0};   /* the window: where room B's light comes from */
    const double corner[3] = {4.0, 0.0, 0.0}; /* a dark corner of room B */
    double bsdf = variance_with(SG_SAMPLING_BSDF, 1.0f, door);
    double good = variance_with(SG_SAMPLING_GUIDED, SG_ALPHA_LEARNED, door);
    double bad = variance_with(SG_SAMPLING_GUIDED, SG_ALPHA_LEARNED, corner);
    double bad_fixed = variance_with(SG_SAMPLING_GUIDED, 0.6f, corner);
    cr_log_info("pixel variance: bsdf %.4g, learned with the door %.4g, learned with a dark corner %.4g, "
                "alpha 0.6 with the corner %.4g",
                bsdf, good, bad, bad_fixed);
    cr_assert_lt(good, 0.8 * bsdf, "a good guide should lower the variance: %.4g vs bsdf %.4g", good, bsdf);
    /* the bad guide costs variance when forced (so this test can fail)... */
    cr_assert_gt(bad_fixed, 1.15 * bsdf, "a bad guide at alpha 0.6: %.4g vs bsdf %.4g", bad_fixed, bsdf);
    /* ...and the learner drops it */
    cr_assert_lt(bad, 1.15 * bsdf, "learned with a bad guide: %.4g vs bsdf %.4g", bad, bsdf);
    cr_assert_lt(bad, 0.7 * bad_fixed, "learned with a bad guide: %.4g vs forced %.4g", bad, bad_fixed);
}

/* Room B is lit only through the window: its light comes from paths of 3
 * and more segments, which albedo roulette cuts as often as any. The
 * learned roulette keeps those that head for the window and cuts those
 * that wander in B: less variance for the rays traced, and the same mean. */
Test(render_learning, learned_roulette_keeps_the_paths_that_bring_light, .timeout = 120)
{
    const double door[3] = {2.0, 1.0, 1.0};
    PassStats st[2];
    double var[2];
    const SgRoulette kinds[2] = {SG_ROULETTE_ALBEDO, SG_ROULETTE_LEARNED};
    for (int k = 0; k < 2; k++)
        var[k] = window_variance((WindowRun){SG_SAMPLING_GUIDED, SG_ALPHA_LEARNED, kinds[k], 12, 13, 128}, door, &st[k]);
    double pixels = 40.0 * 30.0;
    double se = sqrt((var[0] + var[1]) / (128.0 * pixels));
    double work[2] = {var[0] * st[0].rays, var[1] * st[1].rays};
    cr_log_info("albedo roulette: variance %.4g, %.0f rays a pass, mean %.5g; learned: %.4g, %.0f rays, mean %.5g",
                var[0], st[0].rays, st[0].mean, var[1], st[1].rays, st[1].mean);
    cr_assert_lt(fabs(st[0].mean - st[1].mean), 3.0 * se, "means %.5g and %.5g differ by more than 3 SE (%.3g)",
                 st[0].mean, st[1].mean, se);
    cr_assert_lt(work[1], 0.7 * work[0], "variance times rays: learned %.4g, albedo %.4g", work[1], work[0]);
}
