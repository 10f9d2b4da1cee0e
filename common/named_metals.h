/* Metals by name, as the scene readers know them: each one's complex index
 * of refraction in linear RGB (the pbrt reader's "metal-NAME-eta" and
 * "metal-NAME-k" spectra, Mitsuba's conductor `material`). */
#ifndef SG_NAMED_METALS_H
#define SG_NAMED_METALS_H

typedef struct SgNamedMetal {
    const char *name;
    float eta[3], k[3];
} SgNamedMetal;

/* The metal called `name` (case-sensitive, as both formats spell them), or NULL. */
const SgNamedMetal *sg_named_metal(const char *name);
/* The same for the first `length` bytes of name (a token not ended by NUL). */
const SgNamedMetal *sg_named_metal_n(const char *name, unsigned length);

#endif
