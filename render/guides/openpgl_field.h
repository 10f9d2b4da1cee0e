/* Open PGL 0.7 (Intel's Open Path Guiding Library, the peer our guiding is
 * measured against) behind plain C: its field of learned directional
 * distributions over the scene (a kd-tree of regions, each a parallax-aware
 * von Mises-Fisher mixture), one path record and one sampling distribution
 * per thread.
 *
 * Use, as Cycles does: every path records its vertices (segments) as it is
 * traced and hands them to the field's sample storage when it ends; between
 * passes the field learns from them; at a diffuse or glossy vertex the
 * renderer asks for the distribution there (cosine product applied) and
 * mixes it with the BSDF by one-sample MIS.
 *
 * Compiled for real only with SG_HAVE_OPENPGL (`make openpgl`); without it
 * sg_pgl_field_create fails, saying how to get it. One thread index per
 * worker of the renderer's pool, in [0, threads). */
#ifndef SG_OPENPGL_FIELD_H
#define SG_OPENPGL_FIELD_H

#include <stdbool.h>
#include <stddef.h>

#include "error.h"
#include "vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct SgPglField SgPglField;
typedef struct SgPglSegment SgPglSegment; /* a vertex of a thread's current path */

/* Whether this build has Open PGL; sg_pgl_require also says, when it has
 * not, how to get it. */
bool sg_pgl_available(void);
bool sg_pgl_require(SgError *err);

/* A field over the scene's bounds [lo, hi], deterministic (its training
 * does not depend on thread scheduling), for `threads` threads. */
SgPglField *sg_pgl_field_create(Vec3 lo, Vec3 hi, int threads, SgError *err);
void sg_pgl_field_free(SgPglField *f);

/* Learns from the paths ended since the last update, and forgets them. */
void sg_pgl_field_update(SgPglField *f);
/* The field in Open PGL's own serialized form (malloc'ed bytes), and a
 * field read back from such bytes in place of this one's, reporting
 * `updates` training passes. */
bool sg_pgl_field_save(SgPglField *f, unsigned char **data, size_t *size, SgError *err);
bool sg_pgl_field_restore(SgPglField *f, const void *data, size_t size, int updates, SgError *err);

/* Updates so far (training passes), and the samples the last one had. */
int sg_pgl_field_updates(const SgPglField *f);
size_t sg_pgl_field_last_samples(const SgPglField *f);

/* ---- a thread's path record ---- */

/* The next vertex of the thread's path at p: wo toward where the path
 * came from, n the surface normal on wo's side. */
SgPglSegment *sg_pgl_segment_next(SgPglField *f, int thread, Vec3 p, Vec3 wo, Vec3 n);
/* The direction the path leaves by, its pdf and f cos / pdf (delta:
 * a mirror or glass bounce), the surface's eta and roughness. */
void sg_pgl_segment_bounce(SgPglSegment *s, Vec3 wi, float pdf, Vec3 weight, bool delta, float eta,
                           float roughness);
/* Emission at the vertex toward wo, and the MIS weight the path gave it. */
void sg_pgl_segment_emission(SgPglSegment *s, Vec3 le, float mis_weight);
/* Light scattered at the vertex toward wo that the path found another way
 * (next-event estimation, its MIS weight applied), per unit throughput. */
void sg_pgl_segment_scattered(SgPglSegment *s, Vec3 c);
void sg_pgl_segment_survival(SgPglSegment *s, float probability);
/* The path has ended: its samples go to the field's storage. */
void sg_pgl_path_end(SgPglField *f, int thread);

/* ---- a thread's sampling distribution ---- */

/* Prepares the distribution at p (u: a random number that picks among
 * nearby regions), its product with the cosine around n applied. False:
 * the field has nothing learned there yet (sample the BSDF alone). */
bool sg_pgl_guide_at(SgPglField *f, int thread, Vec3 p, Vec3 n, float u);
/* A direction from the prepared distribution (its pdf in *pdf), and the pdf of any. */
Vec3 sg_pgl_guide_sample(SgPglField *f, int thread, float u1, float u2, float *pdf);
float sg_pgl_guide_pdf(SgPglField *f, int thread, Vec3 wi);
/* The density of the prepared distribution before its cosine product: the
 * incoming radiance's, normalized (Cycles' RIS target). */
float sg_pgl_guide_radiance_pdf(SgPglField *f, int thread, Vec3 wi);

/* ---- radiance caches (Open PGL built with OPENPGL_EF_RADIANCE_CACHES) ---- */

/* Whether this build's Open PGL keeps radiance caches. */
bool sg_pgl_has_radiance_caches(void);
/* The prepared distribution's irradiance around n (mis: weighted as the
 * paths' MIS weighed it, what a bounce collects beside the light sample);
 * false without caches. */
bool sg_pgl_guide_irradiance(SgPglField *f, int thread, Vec3 n, bool mis, Vec3 *e);
/* Open PGL's guided (adjoint-driven) Russian roulette: the survival
 * probability, in [min_survival, 1], of a path of throughput beta whose
 * continuation is expected to bring `adjoint` per unit throughput, its
 * pixel `estimate` in all. */
float sg_pgl_guided_survival(Vec3 beta, Vec3 adjoint, Vec3 estimate, float min_survival);

#ifdef __cplusplus
}
#endif
#endif
