#include "film.h"

#include <stdlib.h>
#include <string.h>

bool film_init(Film *f, int width, int height)
{
    size_t values = (size_t)width * height * 3;
    f->width = width;
    f->height = height;
    f->sum = calloc(values, sizeof *f->sum);
    f->last = calloc(values, sizeof *f->last);
    return f->sum && f->last;
}

void film_free(Film *f)
{
    free(f->sum);
    free(f->last);
    f->sum = NULL;
    f->last = NULL;
}

void film_clear(Film *f)
{
    size_t values = (size_t)f->width * f->height * 3;
    memset(f->sum, 0, values * sizeof *f->sum);
    memset(f->last, 0, values * sizeof *f->last);
}

void film_image(const Film *f, int spp, float *rgb)
{
    size_t n = (size_t)f->width * f->height * 3;
    double inv = spp > 0 ? 1.0 / spp : 0.0;
    for (size_t i = 0; i < n; i++)
        rgb[i] = (float)(f->sum[i] * inv);
}
