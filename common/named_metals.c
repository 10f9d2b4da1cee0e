#include "named_metals.h"

#include <string.h>

/* RGB from the measured spectra at 650, 550 and 450 nm (pbrt-v4's named
 * spectra for the first seven; chromium and tungsten for Mitsuba's names). */
static const SgNamedMetal metals[] = {
    {"Ag", {0.155f, 0.117f, 0.138f}, {4.83f, 3.12f, 2.15f}},
    {"Al", {1.66f, 0.880f, 0.521f}, {9.22f, 6.27f, 4.84f}},
    {"Au", {0.143f, 0.375f, 1.44f}, {3.98f, 2.39f, 1.60f}},
    {"Cu", {0.200f, 0.924f, 1.10f}, {3.91f, 2.45f, 2.14f}},
    {"CuZn", {0.444f, 0.527f, 1.09f}, {3.70f, 2.77f, 1.83f}},
    {"MgO", {1.73f, 1.74f, 1.76f}, {0, 0, 0}},
    {"TiO2", {2.58f, 2.74f, 3.03f}, {0, 0, 0}},
    {"Cr", {3.11f, 3.18f, 2.35f}, {3.31f, 3.33f, 3.21f}},
    {"W", {3.76f, 3.51f, 3.39f}, {2.86f, 2.74f, 2.54f}},
};

const SgNamedMetal *sg_named_metal_n(const char *name, unsigned length)
{
    for (size_t i = 0; i < sizeof metals / sizeof metals[0]; i++)
        if (strlen(metals[i].name) == length && !memcmp(metals[i].name, name, length))
            return &metals[i];
    return NULL;
}

const SgNamedMetal *sg_named_metal(const char *name) { return sg_named_metal_n(name, (unsigned)strlen(name)); }
