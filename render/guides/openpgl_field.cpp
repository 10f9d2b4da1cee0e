// Open PGL behind render/guides/openpgl_field.h: C++ because Open PGL's C entry
// points take C++ references and default arguments. Nothing else here.
#include "openpgl_field.h"

#include <cstdio>
#include <cstdlib>
#include <new>
#include <vector>

#include <unistd.h>

#ifdef SG_HAVE_OPENPGL
#include <openpgl/cpp/RussianRoulette.h>
#include <openpgl/openpgl.h>

namespace {

// What a thread keeps: its path's segments and its sampling distribution.
struct ThreadState {
    PGLPathSegmentStorage path = nullptr;
    PGLSurfaceSamplingDistribution distribution = nullptr;
};

pgl_vec3f vec(Vec3 v)
{
    pgl_vec3f r;
    pglVec3f(r, v.x, v.y, v.z);
    return r;
}

// Cycles' choices: direct light is guided too, and its samples carry the
// MIS weight the path gave them.
constexpr bool kGuideDirectLight = true;
constexpr bool kUseNeeMisWeights = true;
constexpr size_t kMaxSamplesPerLeaf = 32000; // Open PGL's default
constexpr size_t kSegmentsPerPath = 128;

} // namespace

struct SgPglField {
    PGLDevice device = nullptr;
    PGLField field = nullptr;
    PGLSampleStorage samples = nullptr; // filled by every thread (concurrently) during a pass
    std::vector<ThreadState> threads;
    int updates = 0;
    size_t last_samples = 0;
};

extern "C" bool sg_pgl_available(void) { return true; }
extern "C" bool sg_pgl_require(SgError *) { return true; }

extern "C" SgPglField *sg_pgl_field_create(Vec3 lo, Vec3 hi, int threads, SgError *err)
{
    SgPglField *f = new (std::nothrow) SgPglField;
    if (!f) {
        sg_fail(err, "Open PGL: out of memory");
        return nullptr;
    }
    // the widest vectors this CPU runs
    PGL_DEVICE_TYPE type = __builtin_cpu_supports("avx2") ? PGL_DEVICE_TYPE_CPU_8 : PGL_DEVICE_TYPE_CPU_4;
    f->device = pglNewDevice(type, threads > 0 ? (size_t)threads : 0);
    PGLFieldArguments args;
    pglFieldArgumentsSetDefaults(args, PGL_SPATIAL_STRUCTURE_KDTREE, PGL_DIRECTIONAL_DISTRIBUTION_PARALLAX_AWARE_VMM,
                                 /*deterministic=*/true, kMaxSamplesPerLeaf);
    f->field = f->device ? pglDeviceNewField(f->device, args) : nullptr;
    f->samples = pglNewSampleStorage();
    if (!f->field || !f->samples) {
        sg_pgl_field_free(f);
        sg_fail(err, "Open PGL: could not create its device, field or sample storage");
        return nullptr;
    }
    pgl_box3f bounds;
    pglBox3f(bounds, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
    pglFieldSetSceneBounds(f->field, bounds);
    f->threads.resize((size_t)(threads > 0 ? threads : 1));
    for (ThreadState &t : f->threads) {
        t.path = pglNewPathSegmentStorage();
        t.distribution = pglFieldNewSurfaceSamplingDistribution(f->field);
        if (!t.path || !t.distribution) {
            sg_pgl_field_free(f);
            sg_fail(err, "Open PGL: could not create a thread's path storage or distribution");
            return nullptr;
        }
        pglPathSegmentStorageReserve(t.path, kSegmentsPerPath);
    }
    return f;
}

extern "C" void sg_pgl_field_free(SgPglField *f)
{
    if (!f)
        return;
    for (ThreadState &t : f->threads) {
        if (t.distribution)
            pglReleaseSurfaceSamplingDistribution(t.distribution);
        if (t.path)
            pglReleasePathSegmentStorage(t.path);
    }
    if (f->samples)
        pglReleaseSampleStorage(f->samples);
    if (f->field)
        pglReleaseField(f->field);
    if (f->device)
        pglReleaseDevice(f->device);
    delete f;
}

extern "C" void sg_pgl_field_update(SgPglField *f)
{
    f->last_samples = pglSampleStorageGetSizeSurface(f->samples);
    pglFieldUpdate(f->field, f->samples);
    pglSampleStorageClear(f->samples);
    f->updates++;
}

// Open PGL serializes a field only to and from a named file: a private
// temporary one, gone when done.
namespace {
bool temp_file(char (&path)[4096], SgError *err)
{
    const char *dir = getenv("TMPDIR");
    snprintf(path, sizeof path, "%s/sg-pgl-field-XXXXXX", dir && *dir ? dir : "/tmp");
    int fd = mkstemp(path);
    if (fd < 0) {
        sg_fail(err, "Open PGL: cannot make a temporary file in %s", dir && *dir ? dir : "/tmp");
        return false;
    }
    close(fd);
    return true;
}
} // namespace

extern "C" bool sg_pgl_field_save(SgPglField *f, unsigned char **data, size_t *size, SgError *err)
{
    char path[4096];
    if (!temp_file(path, err))
        return false;
    bool ok = pglFieldStoreToFile(f->field, path);
    FILE *in = ok ? fopen(path, "rb") : nullptr;
    *data = nullptr;
    *size = 0;
    if (in && fseek(in, 0, SEEK_END) == 0) {
        long n = ftell(in);
        rewind(in);
        *data = n > 0 ? static_cast<unsigned char *>(malloc((size_t)n)) : nullptr;
        ok = *data && fread(*data, 1, (size_t)n, in) == (size_t)n;
        *size = ok ? (size_t)n : 0;
    } else {
        ok = false;
    }
    if (in)
        fclose(in);
    unlink(path);
    if (!ok) {
        free(*data);
        *data = nullptr;
        sg_fail(err, "Open PGL: could not store its field");
    }
    return ok;
}

extern "C" bool sg_pgl_field_restore(SgPglField *f, const void *data, size_t size, int updates, SgError *err)
{
    char path[4096];
    if (!temp_file(path, err))
        return false;
    FILE *out = fopen(path, "wb");
    bool ok = out && fwrite(data, 1, size, out) == size;
    ok = (out && fclose(out) == 0) && ok;
    PGLField field = ok ? pglDeviceNewFieldFromFile(f->device, path) : nullptr;
    unlink(path);
    if (!field) {
        sg_fail(err, "Open PGL could not read the field it holds");
        return false;
    }
    // the threads' distributions belong to the field they were made for
    for (ThreadState &t : f->threads) {
        pglReleaseSurfaceSamplingDistribution(t.distribution);
        t.distribution = pglFieldNewSurfaceSamplingDistribution(field);
    }
    pglReleaseField(f->field);
    f->field = field;
    f->updates = updates;
    for (ThreadState &t : f->threads)
        if (!t.distribution) {
            sg_fail(err, "Open PGL: could not create a thread's distribution");
            return false;
        }
    return true;
}

extern "C" int sg_pgl_field_updates(const SgPglField *f) { return f->updates; }
extern "C" size_t sg_pgl_field_last_samples(const SgPglField *f) { return f->last_samples; }

extern "C" SgPglSegment *sg_pgl_segment_next(SgPglField *f, int thread, Vec3 p, Vec3 wo, Vec3 n)
{
    PGLPathSegmentData *s = pglPathSegmentStorageNextSegment(f->threads[(size_t)thread].path);
    if (!s)
        return nullptr; // the storage is full: the path's later vertices are not recorded
    *s = PGLPathSegmentData{};
    pglPoint3f(s->position, p.x, p.y, p.z);
    s->directionOut = vec(wo);
    s->normal = vec(n);
    return reinterpret_cast<SgPglSegment *>(s);
}

extern "C" void sg_pgl_segment_bounce(SgPglSegment *seg, Vec3 wi, float pdf, Vec3 weight, bool delta, float eta,
                                      float roughness)
{
    if (!seg)
        return;
    PGLPathSegmentData *s = reinterpret_cast<PGLPathSegmentData *>(seg);
    s->directionIn = vec(wi);
    s->pdfDirectionIn = pdf;
    s->scatteringWeight = vec(weight);
    s->isDelta = delta;
    s->eta = eta;
    s->roughness = roughness;
}

extern "C" void sg_pgl_segment_emission(SgPglSegment *seg, Vec3 le, float mis_weight)
{
    if (!seg)
        return;
    PGLPathSegmentData *s = reinterpret_cast<PGLPathSegmentData *>(seg);
    s->directContribution = vec(le);
    s->miWeight = mis_weight;
}

extern "C" void sg_pgl_segment_scattered(SgPglSegment *seg, Vec3 c)
{
    if (!seg)
        return;
    PGLPathSegmentData *s = reinterpret_cast<PGLPathSegmentData *>(seg);
    s->scatteredContribution.x += c.x;
    s->scatteredContribution.y += c.y;
    s->scatteredContribution.z += c.z;
}

extern "C" void sg_pgl_segment_survival(SgPglSegment *seg, float probability)
{
    if (seg)
        reinterpret_cast<PGLPathSegmentData *>(seg)->russianRouletteSurvivalProbability = probability;
}

extern "C" void sg_pgl_path_end(SgPglField *f, int thread)
{
    PGLPathSegmentStorage path = f->threads[(size_t)thread].path;
    pglPathSegmentStoragePropagateSamples(path, f->samples, kGuideDirectLight, kUseNeeMisWeights, true);
    pglPathSegmentStorageClear(path);
}

extern "C" bool sg_pgl_guide_at(SgPglField *f, int thread, Vec3 p, Vec3 n, float u)
{
    if (f->updates == 0)
        return false;
    PGLSurfaceSamplingDistribution d = f->threads[(size_t)thread].distribution;
    pgl_point3f pos;
    pglPoint3f(pos, p.x, p.y, p.z);
    if (!pglFieldInitSurfaceSamplingDistribution(f->field, d, pos, &u))
        return false;
    if (pglSurfaceSamplingDistributionSupportsApplyCosineProduct(d))
        pglSurfaceSamplingDistributionApplyCosineProduct(d, vec(n));
    return true;
}

extern "C" Vec3 sg_pgl_guide_sample(SgPglField *f, int thread, float u1, float u2, float *pdf)
{
    pgl_point2f u;
    pglPoint2f(u, u1, u2);
    pgl_vec3f dir;
    *pdf = pglSurfaceSamplingDistributionSamplePDF(f->threads[(size_t)thread].distribution, u, dir);
    return v3(dir.x, dir.y, dir.z);
}

extern "C" float sg_pgl_guide_pdf(SgPglField *f, int thread, Vec3 wi)
{
    return pglSurfaceSamplingDistributionPDF(f->threads[(size_t)thread].distribution, vec(wi));
}

extern "C" float sg_pgl_guide_radiance_pdf(SgPglField *f, int thread, Vec3 wi)
{
    return pglSurfaceSamplingDistributionIncomingRadiancePDF(f->threads[(size_t)thread].distribution, vec(wi));
}

#ifdef OPENPGL_RADIANCE_CACHES
extern "C" bool sg_pgl_has_radiance_caches(void) { return true; }

extern "C" bool sg_pgl_guide_irradiance(SgPglField *f, int thread, Vec3 n, bool mis, Vec3 *e)
{
    pgl_vec3f r = pglSurfaceSamplingDistributionIrradiance(f->threads[(size_t)thread].distribution, vec(n), mis);
    *e = v3(r.x, r.y, r.z);
    return true;
}
#else
extern "C" bool sg_pgl_has_radiance_caches(void) { return false; }
extern "C" bool sg_pgl_guide_irradiance(SgPglField *, int, Vec3, bool, Vec3 *e)
{
    *e = v3(0, 0, 0);
    return false;
}
#endif

extern "C" float sg_pgl_guided_survival(Vec3 beta, Vec3 adjoint, Vec3 estimate, float min_survival)
{
    return openpgl::cpp::util::GuidedRussianRoulette(vec(beta), vec(adjoint), vec(estimate), min_survival, 1.0f);
}

#else /* built without Open PGL: every entry point fails or does nothing */

extern "C" bool sg_pgl_available(void) { return false; }

extern "C" bool sg_pgl_require(SgError *err)
{
    return sg_fail(err, "this build has no Open PGL: run `make openpgl` (it builds "
                        "../shared/peers/openpgl-0.7.1.tar.gz, or OPENPGL_TARBALL=, or links an installed one "
                        "with OPENPGL_DIR=)");
}

extern "C" SgPglField *sg_pgl_field_create(Vec3, Vec3, int, SgError *err)
{
    sg_pgl_require(err);
    return nullptr;
}

extern "C" void sg_pgl_field_free(SgPglField *) {}
extern "C" void sg_pgl_field_update(SgPglField *) {}
extern "C" bool sg_pgl_field_save(SgPglField *, unsigned char **, size_t *, SgError *err) { return sg_pgl_require(err); }
extern "C" bool sg_pgl_field_restore(SgPglField *, const void *, size_t, int, SgError *err)
{
    return sg_pgl_require(err);
}
extern "C" int sg_pgl_field_updates(const SgPglField *) { return 0; }
extern "C" size_t sg_pgl_field_last_samples(const SgPglField *) { return 0; }
extern "C" SgPglSegment *sg_pgl_segment_next(SgPglField *, int, Vec3, Vec3, Vec3) { return nullptr; }
extern "C" void sg_pgl_segment_bounce(SgPglSegment *, Vec3, float, Vec3, bool, float, float) {}
extern "C" void sg_pgl_segment_emission(SgPglSegment *, Vec3, float) {}
extern "C" void sg_pgl_segment_scattered(SgPglSegment *, Vec3) {}
extern "C" void sg_pgl_segment_survival(SgPglSegment *, float) {}
extern "C" void sg_pgl_path_end(SgPglField *, int) {}
extern "C" bool sg_pgl_guide_at(SgPglField *, int, Vec3, Vec3, float) { return false; }
extern "C" Vec3 sg_pgl_guide_sample(SgPglField *, int, float, float, float *pdf)
{
    *pdf = 0.0f;
    return v3(0, 0, 1);
}
extern "C" float sg_pgl_guide_pdf(SgPglField *, int, Vec3) { return 0.0f; }
extern "C" float sg_pgl_guide_radiance_pdf(SgPglField *, int, Vec3) { return 0.0f; }
extern "C" bool sg_pgl_has_radiance_caches(void) { return false; }
extern "C" bool sg_pgl_guide_irradiance(SgPglField *, int, Vec3, bool, Vec3 *e)
{
    *e = v3(0, 0, 0);
    return false;
}
extern "C" float sg_pgl_guided_survival(Vec3, Vec3, Vec3, float) { return 1.0f; }

#endif
