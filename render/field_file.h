/* A learned guide's field as a file (render --field-out / --field): what a
 * training run learned, for renders that use it frozen, so that a learned
 * guide's preparation is a step of its own, off the clock of the render
 * and shared by the shards of a farm. The layout is in docs/render.md
 * ("Field files"): a header saying what the field was made for (the mode,
 * the scene, the cache, the image size and the options that shape what is
 * learned), then sections of bytes, each named and checked by its hash. */
#ifndef SG_RENDER_FIELD_FILE_H
#define SG_RENDER_FIELD_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "error.h"

#define FIELD_SECTIONS_MAX 4

/* What a field was made for; a render refuses a field whose identity is
 * not its own. `recipe` is readable, so that the refusal can say how. */
typedef struct FieldIdentity {
    char mode[16];
    uint64_t scene_hash, cache_hash;
    char recipe[192];
    uint32_t training_spp; /* passes of training behind it */
} FieldIdentity;

/* Growable bytes: what a guide writes its part of a field into. */
typedef struct FieldBytes {
    unsigned char *data;
    size_t size, capacity;
} FieldBytes;

bool field_bytes_put(FieldBytes *b, const void *data, size_t size);
void field_bytes_free(FieldBytes *b);

/* A section read back: get() copies the next `size` bytes, false past the end. */
typedef struct FieldReader {
    const unsigned char *data;
    size_t size, at;
} FieldReader;

static inline bool field_reader_get(FieldReader *r, void *out, size_t size)
{
    if (size > r->size - r->at)
        return false;
    for (size_t i = 0; i < size; i++)
        ((unsigned char *)out)[i] = r->data[r->at + i];
    r->at += size;
    return true;
}

typedef struct FieldSection {
    char name[16];
    FieldBytes bytes;
} FieldSection;

/* The whole file in memory. */
typedef struct FieldFile {
    FieldIdentity id;
    int section_count;
    FieldSection sections[FIELD_SECTIONS_MAX];
} FieldFile;

/* Written under a temporary name and renamed when complete. */
bool field_file_write(const char *path, const FieldFile *f, SgError *err);
/* Fails, naming the file and the cause, on a missing, foreign, truncated
 * or corrupt file. */
bool field_file_read(const char *path, FieldFile *f, SgError *err);
/* Fails, naming the file, where `got` was made for something else than `want`. */
bool field_identity_check(const char *path, const FieldIdentity *got, const FieldIdentity *want, SgError *err);
/* The section named `name`, or NULL. */
FieldSection *field_file_section(FieldFile *f, const char *name);
FieldSection *field_file_add_section(FieldFile *f, const char *name);
void field_file_free(FieldFile *f);

/* ---- a renderer's field --------------------------------------------------
 * Its sections: "guide", what the guide stores (PathGuideOps.field_store),
 * and with the learned roulette "pixel-noise": the view's identity, then
 * the pixels' sums (PixelNoise) after their pass count noise_spp. */
struct PathGuide;
struct PixelNoise;

/* Writes the field of `guide` and `noise` (NULL: none), made for `id`;
 * the noise is the pixels' of `view` (the camera and image size). */
bool field_file_save(const char *path, const FieldIdentity *id, const struct PathGuide *guide,
                     const struct PixelNoise *noise, int noise_spp, uint64_t view, SgError *err);
/* Reads a field made for `want` into `guide`, and into `noise` (NULL: the
 * render has none, and the file must have none) with its pass count into
 * *noise_spp where the file's noise is for the same `view`; for another
 * view the noise is left as it was (a renderer's then learns anew). */
bool field_file_load(const char *path, const FieldIdentity *want, struct PathGuide *guide, struct PixelNoise *noise,
                     int *noise_spp, uint64_t view, SgError *err);

#endif
