/* The scene every program reads: triangles in world space (double precision,
 * so that a scene far from the origin keeps its detail), materials, lights
 * grouped from emissive triangles, the camera and the build settings.
 * The data model alone: scene_load.h reads it from a JSON, pbrt-v4 or
 * Mitsuba XML file (docs/scene-format.md), scene_builder.h fills it. */
#ifndef SG_SCENE_H
#define SG_SCENE_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "error.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SG_NO_LIGHT UINT32_MAX

typedef enum SgMaterialType {
    SG_MATERIAL_DIFFUSE,    /* Lambert, albedo = diffuse */
    SG_MATERIAL_GLOSSY,     /* diffuse + normalized Phong lobe (specular, exponent) */
    SG_MATERIAL_MIRROR,     /* perfect reflection tinted by specular */
    SG_MATERIAL_DIELECTRIC, /* glass with index ior; GGX-rough where roughness > 0 */
    SG_MATERIAL_CONDUCTOR,  /* metal: GGX microfacets (roughness), complex
                             * Fresnel of eta + i k; a mirror below alpha 1e-3 */
    SG_MATERIAL_COATED_DIFFUSE, /* a diffuse base (diffuse) under a GGX
                                 * dielectric coat of index ior (roughness) */
    SG_MATERIAL_DIFFUSE_TRANSMISSION, /* Lambertian both ways (pbrt-v4's
                                       * diffusetransmission): reflects
                                       * diffuse, lets transmittance through */
} SgMaterialType;

/* What a texture's value is made of: another texture or a constant. */
typedef struct SgTextureInput {
    uint32_t texture; /* 1 + index in scene->textures; 0: the constant `value` */
    float value[3];
} SgTextureInput;

typedef enum SgTextureKind {
    SG_TEXTURE_IMAGE,        /* an image file, looked up at (u, v) */
    SG_TEXTURE_SCALE,        /* input[0] times input[1] */
    SG_TEXTURE_MIX,          /* (1 - input[2]) input[0] + input[2] input[1] */
    SG_TEXTURE_CHECKERBOARD, /* input[0] on the even squares of (u, v), input[1] on the odd */
} SgTextureKind;

typedef enum SgTextureWrap { SG_WRAP_REPEAT, SG_WRAP_CLAMP, SG_WRAP_BLACK } SgTextureWrap;

/* A texture as pbrt-v4 defines its imagemap, scale, mix and checkerboard
 * (2D, uv mapping). Its lookup coordinates are
 *   s = uscale u + udelta,  t = vscale v + vdelta. */
typedef struct SgTexture {
    SgTextureKind kind;
    float uscale, vscale, udelta, vdelta;
    /* image */
    char *path;       /* NULL: the file could not be read (then mean is grey 0.5) */
    float gamma;      /* how its values are encoded: 0 linear, -1 sRGB, else an exponent */
    float scale;      /* multiplies the value */
    bool invert;      /* 1 - value (after scale), as pbrt */
    SgTextureWrap wrap;
    SgTextureInput input[3];
    float mean[3];    /* the average value, for what cannot look up (u, v) */
} SgTexture;

typedef struct SgMaterial {
    char name[64];
    SgMaterialType type;
    float diffuse[3];  /* Kd: albedo */
    float specular[3]; /* Ks */
    float exponent;    /* Ns: Phong exponent */
    float ior;         /* Ni */
    float emission[3]; /* Ke: emitted radiance; non-zero makes its triangles lights */
    float roughness[2]; /* conductor, coated diffuse, dielectric: GGX alpha along the tangent and bitangent */
    float eta[3], k[3]; /* conductor: complex index of refraction per channel */
    /* 1 + index in scene->textures of what varies `diffuse` over the
     * surface (diffuse, glossy and coated diffuse: the albedo; conductor:
     * its reflectance at normal incidence, in place of eta and k); 0: none.
     * `diffuse` then holds the texture's mean. */
    uint32_t diffuse_texture;
    float transmittance[3]; /* diffuse transmission: what passes to the other side */
    /* A cut-out (pbrt-v4's shape "alpha", Mitsuba's mask): rays pass
     * through where alpha_texture's value is below 0.5, or, for a constant
     * alpha, with probability 1 - alpha (pbrt-v4's stochastic alpha). Not a
     * blend: a ray either meets the surface or does not. */
    bool cutout;
    float alpha;
    uint32_t alpha_texture; /* 1 + index in scene->textures; 0: the constant alpha */
    /* dielectric: the absorption coefficient of what it encloses, per unit
     * of world length (Beer-Lambert along the path inside); 0: clear */
    float sigma_a[3];
    /* Shading normals, 1 + index in scene->textures (0: none): a tangent-
     * space normal map (rgb = (n + 1) / 2, along the mesh's u, v and normal),
     * or a bump map, a displacement along the normal of bump_scale times
     * its value (pbrt's "displacement"; the first channel). */
    uint32_t normal_texture, bump_texture;
    float bump_scale;
} SgMaterial;

/* pbrt-v4's conductor given a reflectance r instead of eta and k: eta 1 and
 * the k whose normal-incidence Fresnel is r (the pbrt loader for a constant
 * reflectance, the renderer for a textured one). */
static inline float sg_conductor_k_of_reflectance(float r)
{
    r = fminf(fmaxf(r, 0.0f), 0.9999f);
    return 2.0f * sqrtf(r) / sqrtf(1.0f - r);
}

/* A light is a connected set of emissive triangles of one material (a quad
 * is one light, not two). Its triangles are
 * scene->light_triangles[first_triangle .. first_triangle + triangle_count). */
typedef struct SgLight {
    double position[3]; /* area-weighted centroid */
    double normal[3];   /* unit, area-weighted mean of the triangle normals */
    double area;
    float radiance[3];  /* emitted radiance (one-sided, towards the normal) */
    double power;       /* pi * area * luminance(radiance): for choosing lights */
    uint32_t first_triangle;
    uint32_t triangle_count;
} SgLight;

/* A light that is not a surface (pbrt-v4's LightSource statement, or the
 * JSON scene's sky, sun, point and spot): the renderer samples it directly;
 * area lights are SgLight. Radiometric values are RGB, scale applied. */
typedef enum SgLightSourceKind {
    SG_LIGHT_POINT,    /* intensity from a point, the same every way */
    SG_LIGHT_SPOT,     /* a point whose intensity falls off smoothly from
                        * cos_falloff_start to nothing at cos_cone (pbrt-v4) */
    SG_LIGHT_DISTANT,  /* the sun: light from one direction (or a cone of
                        * angular_radius), irradiance `rgb` on a plane facing it */
    SG_LIGHT_INFINITE, /* the sky: radiance `rgb` from every direction,
                        * times an environment image where one is given */
} SgLightSourceKind;

/* How an environment image covers the sphere of directions (light space, z up). */
typedef enum SgEnvironmentLayout {
    SG_ENVIRONMENT_BY_SHAPE,   /* a square image is equal-area, a 2:1 one lat-long */
    SG_ENVIRONMENT_EQUAL_AREA, /* pbrt-v4's equal-area square (octahedral) map */
    SG_ENVIRONMENT_LATLONG,    /* the usual 2:1 map: u the azimuth, v from +z down to -z */
} SgEnvironmentLayout;

typedef struct SgLightSource {
    SgLightSourceKind kind;
    /* point, spot: intensity (radiance times area, per steradian);
     * distant: irradiance on a plane facing it; infinite: radiance
     * (multiplying the image's texels where there is an image) */
    float rgb[3];
    double position[3];   /* point, spot (world) */
    double direction[3];  /* unit, the way the light travels: spot's axis, the sun's rays */
    double cos_cone, cos_falloff_start; /* spot */
    double angular_radius; /* distant: radians of the sun's disk; 0: a delta direction */
    char *image_path;     /* infinite: the environment image, or NULL: constant */
    /* infinite: an image made at load time (a parametric sky, sunsky.h) in
     * place of a file: RGB, row by row from the top, image_width x
     * image_height; NULL: none */
    float *image_pixels;
    int image_width, image_height;
    SgEnvironmentLayout layout;
    /* infinite with an image: the irradiance of an upward-facing plane the
     * image is scaled to (pbrt-v4's "illuminance"); 0: as it is */
    double illuminance;
    double light_to_world[3][3]; /* infinite: rotation from light space (z up) to world */
    bool has_portal;      /* infinite: a window the sky is seen through (pbrt-v4's "portal") */
    double portal[4][3];
} SgLightSource;

typedef struct SgCamera {
    double position[3];
    double look_at[3];
    double up[3];
    double fov_deg; /* vertical field of view in degrees */
    int width, height;
} SgCamera;

/* The maximum path length where a scene gives none (a scene file's
 * render.max_depth; the renderer's for a scene made in code). */
#define SG_MAX_DEPTH_DEFAULT 8

typedef struct SgRenderSettings {
    int spp;          /* default samples per pixel (0: not given) */
    int max_depth;    /* maximum path length in segments from the camera (1: what it sees) */
    double exposure;  /* PNG exposure in stops */
} SgRenderSettings;

/* The most voxels along a grid's longest side, wherever a resolution is
 * given (the scene's "voxel" block, voxelize --resolution). */
#define SG_VOXEL_RESOLUTION_MAX 4096

typedef struct SgScene {
    char path[4096];          /* the scene file as given */

    uint32_t vertex_count;
    double *positions;        /* 3 * vertex_count, world space */
    uint32_t triangle_count;
    uint32_t *indices;        /* 3 * triangle_count */
    uint32_t *triangle_material; /* triangle_count */
    uint32_t *triangle_light; /* triangle_count: light index or SG_NO_LIGHT */

    float *uvs;               /* 2 * vertex_count texture coordinates, or NULL: none in the scene */

    uint32_t material_count;
    SgMaterial *materials;
    uint32_t texture_count;
    SgTexture *textures;

    uint32_t light_count;
    SgLight *lights;
    uint32_t *light_triangles; /* triangle ids grouped by light */

    /* Point, spot, distant and infinite lights, in the order read. */
    uint32_t light_source_count;
    SgLightSource *light_sources;

    bool has_camera;
    SgCamera camera;
    SgRenderSettings render;
    int voxel_resolution;     /* from "voxel": {"resolution"}, 1..SG_VOXEL_RESOLUTION_MAX; 0 if not given */

    double bounds_min[3], bounds_max[3]; /* of all triangles */
    uint32_t degenerate_dropped; /* zero-area triangles left out when loading */

    /* Identity of what the precompute depends on: geometry, materials'
     * emission and lights; not the camera. Same scene in, same hash out. */
    uint64_t geometry_hash;
    /* Identity of the scene's text: FNV-1a 64 of every scene file the
     * loader read (the JSON, or the pbrt file and its Includes), in the
     * order read. With geometry_hash, what a render farm's shards of one
     * render must share. */
    uint64_t source_hash;

    /* What the loader could not honour (pbrt statements it does not
     * support, approximations made): one line each, no trailing newline.
     * The loader never prints; programs call sg_scene_print_warnings. */
    uint32_t warning_count;
    char **warnings;
} SgScene;

/* What the precompute takes as its lights and the guide follows, in this
 * order: the area lights (SgLight, same index), the point and spot lights,
 * the outside where a sky shines (the air beyond the scene's bounds,
 * reached through the openings), then each sun (the air its rays reach). */
typedef enum SgGuideLightKind {
    SG_GUIDE_LIGHT_AREA,
    SG_GUIDE_LIGHT_POINT,   /* a point or spot light */
    SG_GUIDE_LIGHT_OUTSIDE, /* the sky, reached through the openings */
    SG_GUIDE_LIGHT_SUN,     /* a distant light: the air its rays reach, through the openings it shines through */
} SgGuideLightKind;

typedef struct SgGuideLight {
    SgGuideLightKind kind;
    uint32_t index;     /* area: the SgLight; point, sun: the SgLightSource; outside: unused */
    double position[3]; /* area: centroid; point: its position; outside, sun: unused */
    double normal[3];   /* area: mean normal; spot: its axis; sun: the way its rays travel; else 0 */
    double power;       /* for choosing which light to follow (an image sky: its colour's, the map unread) */
} SgGuideLight;

uint32_t sg_scene_guide_light_count(const SgScene *scene);
/* Guide light i < sg_scene_guide_light_count(scene). */
SgGuideLight sg_scene_guide_light(const SgScene *scene, uint32_t i);
/* A sky or a sun: the outside of the scene sends light in. */
bool sg_scene_lit_from_outside(const SgScene *scene);

void sg_scene_free(SgScene *scene);

/* Prints each warning as "program: warning: line" to out. */
void sg_scene_print_warnings(const SgScene *scene, const char *program, FILE *out);

/* Geometric (unnormalized) normal of triangle t: (b-a) x (c-a). */
void sg_scene_triangle_normal(const SgScene *scene, uint32_t t, double n[3]);

#ifdef __cplusplus
}
#endif
#endif
