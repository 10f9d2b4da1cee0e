#include "textures.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "texture_images.h"

struct TextureSet {
    uint32_t count;
    SgTexture *textures;     /* the scene's, paths not owned */
    SgTextureImage **images; /* per texture: its opened image, or NULL */
    SgTextureImages *cache;
    float *uvs;              /* 2 per vertex, or NULL: every lookup at (0, 0) */
    const uint32_t *indices;
};

bool textures_needed(const SgScene *s)
{
    for (uint32_t m = 0; m < s->material_count; m++)
        if (s->materials[m].diffuse_texture || (s->materials[m].cutout && s->materials[m].alpha_texture) ||
            s->materials[m].normal_texture || s->materials[m].bump_texture)
            return true;
    return false;
}

TextureSet *texture_set_create(const SgScene *s, const uint32_t *indices, int threads, double cache_mb,
                               const char *path, SgError *err)
{
    TextureSet *t = calloc(1, sizeof *t);
    if (!t)
        return sg_fail(err, "%s: out of memory", path), NULL;
    t->count = s->texture_count;
    t->indices = indices;
    t->textures = calloc(s->texture_count + 1, sizeof *t->textures);
    t->images = calloc(s->texture_count + 1, sizeof *t->images);
    if (s->uvs && (t->uvs = malloc(2 * sizeof(float) * (s->vertex_count + 1))))
        memcpy(t->uvs, s->uvs, 2 * sizeof(float) * s->vertex_count);
    t->cache = sg_texture_images_create(threads, cache_mb > 0 ? cache_mb : TEXTURE_CACHE_MB_DEFAULT, err);
    if (!t->textures || !t->images || (s->uvs && !t->uvs) || !t->cache) {
        bool cache_failed = !t->cache; /* it said why */
        texture_set_free(t);
        return cache_failed ? NULL : (sg_fail(err, "%s: out of memory", path), NULL);
    }
    for (uint32_t i = 0; i < s->texture_count; i++) {
        t->textures[i] = s->textures[i];
        /* inputs name earlier textures only (pbrt defines before use): no cycle */
        for (int k = 0; k < 3; k++)
            if (t->textures[i].input[k].texture > i) {
                texture_set_free(t);
                return sg_fail(err, "%s: texture %u uses texture %u, defined after it", path, i,
                               s->textures[i].input[k].texture - 1), NULL;
            }
        if (s->textures[i].kind == SG_TEXTURE_IMAGE && s->textures[i].path &&
            !(t->images[i] = sg_texture_images_open(t->cache, s->textures[i].path, err))) {
            texture_set_free(t);
            return NULL;
        }
    }
    for (uint32_t m = 0; m < s->material_count; m++)
        if (s->materials[m].diffuse_texture > s->texture_count) {
            texture_set_free(t);
            return sg_fail(err, "%s: material \"%s\" has no texture %u", path, s->materials[m].name,
                           s->materials[m].diffuse_texture - 1), NULL;
        }
    return t;
}

void texture_set_free(TextureSet *t)
{
    if (!t)
        return;
    sg_texture_images_free(t->cache);
    free(t->images);
    free(t->textures);
    free(t->uvs);
    free(t);
}

static float decode(float v, float gamma)
{
    if (gamma == 0.0f)
        return v;
    return gamma < 0.0f ? (float)sg_srgb_to_linear(v) : powf(sg_maxf(v, 0.0f), gamma);
}

static Vec3 input_value(const TextureSet *t, const SgTextureInput *in, float u, float v, int thread)
{
    return in->texture ? texture_set_eval(t, in->texture, u, v, thread)
                       : v3(in->value[0], in->value[1], in->value[2]);
}

Vec3 texture_set_eval(const TextureSet *t, uint32_t texture, float u, float v, int thread)
{
    const SgTexture *tex = &t->textures[texture - 1];
    float s = tex->uscale * u + tex->udelta, tc = tex->vscale * v + tex->vdelta;
    switch (tex->kind) {
    case SG_TEXTURE_IMAGE: {
        SgTextureImage *image = t->images[texture - 1];
        if (!image)
            return v3(tex->mean[0], tex->mean[1], tex->mean[2]);
        /* pbrt: t = 0 is the image's last row */
        float rgb[3];
        sg_texture_image_lookup(t->cache, image, thread, s, 1.0f - tc, tex->wrap, rgb);
        for (int c = 0; c < 3; c++) {
            rgb[c] = decode(rgb[c], tex->gamma) * tex->scale;
            if (tex->invert)
                rgb[c] = sg_maxf(0.0f, 1.0f - rgb[c]);
        }
        return v3(rgb[0], rgb[1], rgb[2]);
    }
    case SG_TEXTURE_SCALE:
        return v3_mul(input_value(t, &tex->input[0], u, v, thread), input_value(t, &tex->input[1], u, v, thread));
    case SG_TEXTURE_MIX: {
        float amount = input_value(t, &tex->input[2], u, v, thread).x;
        Vec3 a = input_value(t, &tex->input[0], u, v, thread), b = input_value(t, &tex->input[1], u, v, thread);
        return v3_add(v3_scale(a, 1.0f - amount), v3_scale(b, amount));
    }
    case SG_TEXTURE_CHECKERBOARD: {
        bool odd = ((long long)floorf(s) + (long long)floorf(tc)) & 1;
        return input_value(t, &tex->input[odd], u, v, thread);
    }
    }
    return v3(tex->mean[0], tex->mean[1], tex->mean[2]);
}

bool texture_set_triangle_uvs(const TextureSet *t, uint32_t tri, float uv[3][2])
{
    if (!t->uvs)
        return false;
    const uint32_t *id = t->indices + 3 * (size_t)tri;
    for (int k = 0; k < 3; k++) {
        uv[k][0] = t->uvs[2 * (size_t)id[k]];
        uv[k][1] = t->uvs[2 * (size_t)id[k] + 1];
    }
    return true;
}

Vec3 texture_set_eval_at(const TextureSet *t, uint32_t texture, uint32_t tri, float b1, float b2, int thread)
{
    float u = 0.0f, v = 0.0f;
    if (t->uvs) {
        const uint32_t *id = t->indices + 3 * (size_t)tri;
        const float *a = t->uvs + 2 * (size_t)id[0], *b = t->uvs + 2 * (size_t)id[1], *c = t->uvs + 2 * (size_t)id[2];
        float b0 = 1.0f - b1 - b2;
        u = b0 * a[0] + b1 * b[0] + b2 * c[0];
        v = b0 * a[1] + b1 * b[1] + b2 * c[1];
    }
    return texture_set_eval(t, texture, u, v, thread);
}

size_t texture_set_cache_bytes(const TextureSet *t, size_t *images)
{
    return sg_texture_images_cache_bytes(t->cache, images);
}
