#include "image_average.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "color.h"
#include "image_io.h"

double sg_image_default_gamma(const char *path)
{
    static const char *const linear[] = {".exr", ".pfm", ".hdr"};
    size_t n = strlen(path);
    for (size_t i = 0; i < sizeof linear / sizeof *linear; i++) {
        size_t k = strlen(linear[i]);
        bool match = n >= k;
        for (size_t j = 0; match && j < k; j++) {
            char a = path[n - k + j];
            match = (a >= 'A' && a <= 'Z' ? a + 32 : a) == linear[i][j];
        }
        if (match)
            return 0;
    }
    return -1;
}

bool sg_image_average(SgImageAverages *c, const char *path, double gamma, float out[3], bool *first)
{
    if (first)
        *first = false;
    for (size_t i = 0; i < c->count; i++)
        if (!strcmp(c->entries[i].path, path) && c->entries[i].gamma == gamma) {
            if (c->entries[i].readable)
                memcpy(out, c->entries[i].value, 3 * sizeof(float));
            return c->entries[i].readable;
        }
    if (first)
        *first = true;
    int w = 0, h = 0;
    float *rgb = NULL;
    SgError ignored = {0};
    bool readable = sg_image_read(path, &w, &h, &rgb, &ignored);
    float mean[3] = {0, 0, 0};
    if (readable) {
        double sum[3] = {0, 0, 0};
        /* A few hundred thousand pixels give the mean well enough. */
        size_t step = 1 + (size_t)w * (size_t)h / 262144, n = 0;
        for (size_t i = 0; i < (size_t)w * (size_t)h; i += step, n++)
            for (int k = 0; k < 3; k++) {
                double v = rgb[3 * i + k];
                v = !isfinite(v) || v < 0 ? 0 : v;
                sum[k] += gamma == 0 ? v : gamma < 0 ? sg_srgb_to_linear(v) : pow(v, gamma);
            }
        for (int k = 0; k < 3; k++)
            out[k] = mean[k] = (float)(sum[k] / (double)(n ? n : 1));
    }
    free(rgb);
    /* a cache entry lost to a full memory only costs a second read */
    if (c->count == c->capacity) {
        size_t capacity = c->capacity ? 2 * c->capacity : 16;
        SgImageAverage *grown = realloc(c->entries, capacity * sizeof *grown);
        if (!grown)
            return readable;
        c->entries = grown;
        c->capacity = capacity;
    }
    SgImageAverage *a = &c->entries[c->count];
    if ((a->path = strdup(path))) {
        a->gamma = gamma;
        a->readable = readable;
        memcpy(a->value, mean, sizeof a->value);
        c->count++;
    }
    return readable;
}

void sg_image_averages_free(SgImageAverages *c)
{
    for (size_t i = 0; i < c->count; i++)
        free(c->entries[i].path);
    free(c->entries);
    memset(c, 0, sizeof *c);
}
