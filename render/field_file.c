#include "field_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "guides/path_guide.h"
#include "hash.h"
#include "input_file.h"
#include "output_file.h"
#include "pixel_noise.h"

static const char field_magic[8] = {'S', 'G', 'F', 'I', 'E', 'L', 'D', '\x1a'};
#define FIELD_VERSION 6u /* 2: openpgl's section counts its passes; 3: guided's learned axes; 4: its histograms; 5: its portal shares; 6: any view of the scene (the pixel noise kept for its own) */
/* A field is a few regions' worth of numbers per scene cell: far below this */
#define FIELD_LIMIT ((size_t)4 << 30)

bool field_bytes_put(FieldBytes *b, const void *data, size_t size)
{
    if (size > b->capacity - b->size) {
        size_t cap = b->capacity ? b->capacity : 4096;
        while (cap - b->size < size)
            cap *= 2;
        unsigned char *d = realloc(b->data, cap);
        if (!d)
            return false;
        b->data = d;
        b->capacity = cap;
    }
    if (size)
        memcpy(b->data + b->size, data, size);
    b->size += size;
    return true;
}

void field_bytes_free(FieldBytes *b)
{
    free(b->data);
    *b = (FieldBytes){0};
}

FieldSection *field_file_section(FieldFile *f, const char *name)
{
    for (int i = 0; i < f->section_count; i++)
        if (!strncmp(f->sections[i].name, name, sizeof f->sections[i].name))
            return &f->sections[i];
    return NULL;
}

FieldSection *field_file_add_section(FieldFile *f, const char *name)
{
    if (f->section_count >= FIELD_SECTIONS_MAX)
        return NULL;
    FieldSection *s = &f->sections[f->section_count++];
    memset(s, 0, sizeof *s);
    snprintf(s->name, sizeof s->name, "%s", name);
    return s;
}

void field_file_free(FieldFile *f)
{
    for (int i = 0; i < f->section_count; i++)
        field_bytes_free(&f->sections[i].bytes);
    f->section_count = 0;
}

/* ---- the header, little-endian whatever the machine ---- */

static void put_u32(FieldBytes *b, uint32_t v, bool *ok)
{
    unsigned char c[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    *ok = *ok && field_bytes_put(b, c, 4);
}

static void put_u64(FieldBytes *b, uint64_t v, bool *ok)
{
    put_u32(b, (uint32_t)v, ok);
    put_u32(b, (uint32_t)(v >> 32), ok);
}

static bool get_u32(FieldReader *r, uint32_t *v)
{
    unsigned char c[4];
    if (!field_reader_get(r, c, 4))
        return false;
    *v = (uint32_t)c[0] | (uint32_t)c[1] << 8 | (uint32_t)c[2] << 16 | (uint32_t)c[3] << 24;
    return true;
}

static bool get_u64(FieldReader *r, uint64_t *v)
{
    uint32_t lo, hi;
    if (!get_u32(r, &lo) || !get_u32(r, &hi))
        return false;
    *v = (uint64_t)hi << 32 | lo;
    return true;
}

static bool header_bytes(const FieldFile *f, FieldBytes *h)
{
    bool ok = field_bytes_put(h, field_magic, sizeof field_magic);
    put_u32(h, FIELD_VERSION, &ok);
    put_u32(h, (uint32_t)f->section_count, &ok);
    ok = ok && field_bytes_put(h, f->id.mode, sizeof f->id.mode);
    put_u64(h, f->id.scene_hash, &ok);
    put_u64(h, f->id.cache_hash, &ok);
    ok = ok && field_bytes_put(h, f->id.recipe, sizeof f->id.recipe);
    put_u32(h, f->id.training_spp, &ok);
    for (int i = 0; i < f->section_count; i++) {
        const FieldSection *s = &f->sections[i];
        ok = ok && field_bytes_put(h, s->name, sizeof s->name);
        put_u64(h, s->bytes.size, &ok);
        put_u64(h, sg_hash_bytes(SG_HASH_INIT, s->bytes.data, s->bytes.size), &ok);
    }
    put_u64(h, sg_hash_bytes(SG_HASH_INIT, h->data, h->size), &ok);
    return ok;
}

bool field_file_write(const char *path, const FieldFile *f, SgError *err)
{
    FieldBytes h = {0};
    if (!header_bytes(f, &h)) {
        field_bytes_free(&h);
        return sg_fail(err, "%s: out of memory", path);
    }
    SgOutputFile out;
    if (!sg_output_open(&out, path, err)) {
        field_bytes_free(&h);
        return false;
    }
    bool ok = fwrite(h.data, 1, h.size, out.file) == h.size;
    for (int i = 0; ok && i < f->section_count; i++)
        ok = fwrite(f->sections[i].bytes.data, 1, f->sections[i].bytes.size, out.file) == f->sections[i].bytes.size;
    field_bytes_free(&h);
    if (!ok) {
        sg_output_abort(&out);
        return sg_fail(err, "%s: cannot write the field", path);
    }
    return sg_output_commit(&out, err);
}

bool field_file_read(const char *path, FieldFile *f, SgError *err)
{
    memset(f, 0, sizeof *f);
    char *data;
    size_t size;
    if (!sg_read_file(path, "field", FIELD_LIMIT, &data, &size, err))
        return false;
    FieldReader r = {(const unsigned char *)data, size, 0};
    char magic[8];
    uint32_t version, sections;
    bool ok = field_reader_get(&r, magic, sizeof magic) && !memcmp(magic, field_magic, sizeof magic);
    if (!ok) {
        free(data);
        return sg_fail(err, "%s: not a field file (render --field-out makes them)", path);
    }
    ok = get_u32(&r, &version) && get_u32(&r, &sections);
    if (ok && version != FIELD_VERSION) {
        free(data);
        return sg_fail(err, "%s: a field of version %u; this render reads version %u", path, version, FIELD_VERSION);
    }
    ok = ok && sections <= FIELD_SECTIONS_MAX && field_reader_get(&r, f->id.mode, sizeof f->id.mode) &&
         get_u64(&r, &f->id.scene_hash) && get_u64(&r, &f->id.cache_hash) &&
         field_reader_get(&r, f->id.recipe, sizeof f->id.recipe) && get_u32(&r, &f->id.training_spp);
    f->id.mode[sizeof f->id.mode - 1] = '\0';
    f->id.recipe[sizeof f->id.recipe - 1] = '\0';
    uint64_t sizes[FIELD_SECTIONS_MAX], hashes[FIELD_SECTIONS_MAX];
    char names[FIELD_SECTIONS_MAX][16];
    for (uint32_t i = 0; ok && i < sections; i++)
        ok = field_reader_get(&r, names[i], sizeof names[i]) && get_u64(&r, &sizes[i]) && get_u64(&r, &hashes[i]);
    uint64_t header_hash, want = sg_hash_bytes(SG_HASH_INIT, r.data, r.at);
    ok = ok && get_u64(&r, &header_hash) && header_hash == want;
    if (!ok) {
        free(data);
        return sg_fail(err, "%s: corrupt or truncated field header", path);
    }
    for (uint32_t i = 0; i < sections; i++) {
        FieldSection *s = field_file_add_section(f, "");
        memcpy(s->name, names[i], sizeof s->name);
        s->name[sizeof s->name - 1] = '\0';
        if (sizes[i] > r.size - r.at) {
            free(data);
            field_file_free(f);
            return sg_fail(err, "%s: truncated: its section %s needs %llu more bytes than the file has", path,
                           s->name, (unsigned long long)(sizes[i] - (r.size - r.at)));
        }
        if (!field_bytes_put(&s->bytes, r.data + r.at, sizes[i])) {
            free(data);
            field_file_free(f);
            return sg_fail(err, "%s: out of memory", path);
        }
        r.at += sizes[i];
        if (sg_hash_bytes(SG_HASH_INIT, s->bytes.data, s->bytes.size) != hashes[i]) {
            free(data);
            field_file_free(f);
            return sg_fail(err, "%s: corrupt: its section %s does not match its checksum", path, names[i]);
        }
    }
    bool trailing = r.at != r.size;
    free(data);
    if (trailing) {
        field_file_free(f);
        return sg_fail(err, "%s: corrupt: bytes after its last section", path);
    }
    return true;
}

bool field_identity_check(const char *path, const FieldIdentity *got, const FieldIdentity *want, SgError *err)
{
    if (strcmp(got->mode, want->mode))
        return sg_fail(err, "%s: a field of --sampling %s, not %s", path, got->mode, want->mode);
    if (got->scene_hash != want->scene_hash)
        return sg_fail(err, "%s: a field learned on another scene (or another version of it): train it again", path);
    if (got->cache_hash != want->cache_hash)
        return sg_fail(err, "%s: a field learned with another importance cache: train it again", path);
    if (strcmp(got->recipe, want->recipe))
        return sg_fail(err, "%s: a field learned for %s; this render is %s", path, got->recipe, want->recipe);
    return true;
}

bool field_file_save(const char *path, const FieldIdentity *id, const PathGuide *guide, const PixelNoise *noise,
                     int noise_spp, uint64_t view, SgError *err)
{
    FieldFile f = {0};
    f.id = *id;
    FieldSection *g = field_file_add_section(&f, "guide");
    bool ok = guide->ops->field_store(guide, &g->bytes);
    if (ok && noise) { /* the learned roulette's knowledge of the pixels */
        FieldSection *n = field_file_add_section(&f, "pixel-noise");
        size_t pixels = (size_t)noise->width * noise->height;
        int32_t spp = noise_spp;
        ok = field_bytes_put(&n->bytes, &view, sizeof view) && field_bytes_put(&n->bytes, &spp, sizeof spp) &&
             field_bytes_put(&n->bytes, noise->sum, pixels * sizeof *noise->sum) &&
             field_bytes_put(&n->bytes, noise->sum_sq, pixels * sizeof *noise->sum_sq);
    }
    if (!ok) {
        field_file_free(&f);
        return sg_fail(err, "%s: out of memory for the field", path);
    }
    ok = field_file_write(path, &f, err);
    field_file_free(&f);
    return ok;
}

bool field_file_load(const char *path, const FieldIdentity *want, PathGuide *guide, PixelNoise *noise,
                     int *noise_spp, uint64_t view, SgError *err)
{
    FieldFile f;
    if (!field_file_read(path, &f, err))
        return false;
    bool ok = field_identity_check(path, &f.id, want, err);
    FieldSection *g = field_file_section(&f, "guide");
    FieldSection *n = field_file_section(&f, "pixel-noise");
    size_t pixels = noise ? (size_t)noise->width * noise->height : 0;
    size_t noise_size = sizeof(uint64_t) + sizeof(int32_t) + 2 * pixels * sizeof(double);
    if (ok && (!g || (noise != NULL) != (n != NULL) || (n && n->bytes.size < sizeof(uint64_t) + sizeof(int32_t))))
        ok = sg_fail(err, "%s: corrupt: its sections are not those of a --sampling %s field", path, f.id.mode);
    /* the pixels' noise serves the view it was learned for alone (another
     * camera or size: the learned roulette learns its pixels anew) */
    uint64_t noise_view = 0;
    if (ok && n)
        memcpy(&noise_view, n->bytes.data, sizeof noise_view);
    bool same_view = ok && n && noise_view == view && n->bytes.size == noise_size;
    if (ok && n && noise_view == view && n->bytes.size != noise_size)
        ok = sg_fail(err, "%s: corrupt: its pixel noise is not the size of its view", path);
    if (ok) {
        FieldReader in = {g->bytes.data, g->bytes.size, 0};
        SgError e = {0};
        if (!guide->ops->field_load(guide, &in, &e) || in.at != in.size)
            ok = sg_fail(err, "%s: %s", path, e.message[0] ? e.message : "its guide's part is corrupt");
    }
    if (ok && same_view) {
        const uint8_t *at = n->bytes.data + sizeof noise_view;
        int32_t spp;
        memcpy(&spp, at, sizeof spp);
        memcpy(noise->sum, at + sizeof spp, pixels * sizeof(double));
        memcpy(noise->sum_sq, at + sizeof spp + pixels * sizeof(double), pixels * sizeof(double));
        *noise_spp = spp > 0 ? spp : 0;
    }
    field_file_free(&f);
    return ok;
}
