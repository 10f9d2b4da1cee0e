/* Mitsuba scene files (.xml), Mitsuba 3's dialect and the 0.5/0.6 one
 * (told apart by the scene's version, camelCase names upgraded as
 * Mitsuba 3 does), onto the scene builder as the pbrt-v4 reader does.
 * sg_scene_load (scene_load.c) dispatches here on the ".xml" extension.
 *
 * What it takes and maps to what:
 *   structure  <default> and $name, id / <ref> (nested ids too), <alias>,
 *              <include> (cycles refused), <path>; <transform> steps
 *              translate, rotate, scale, matrix, lookat (an <animation>:
 *              its first key)
 *   shapes     obj (through the mesh-file loader), ply, serialized (with
 *              shape_index), rectangle, cube, sphere, disk, cylinder as
 *              meshes of their true area, shapegroup / instance;
 *              flip_normals; face_normals read (shading uses the
 *              triangles' own normals anyway)
 *   bsdfs      diffuse; plastic, roughplastic -> coated diffuse; conductor,
 *              roughconductor -> conductor (named metals, eta/k, "none" a
 *              mirror, a specular tint folded into the reflectance);
 *              dielectric, roughdielectric, thindielectric -> dielectric;
 *              phong -> glossy; twosided, mask, bumpmap, normalmap -> their
 *              inner bsdf; blendbsdf -> the blend of two diffuse, else the
 *              heavier; null -> the shape left out
 *   textures   bitmap (uv scale and offset), checkerboard, scale; rgb,
 *              srgb, spectrum (constant or wavelength:value, to RGB through
 *              the CIE 1931 fit), blackbody (its colour)
 *   emitters   area, point, spot, directional, constant, envmap (lat-long,
 *              scale, to_world); sunsky and the rest: a warning
 *   sensor     perspective (thinlens as a pinhole): fov and fov_axis (x,
 *              y, diagonal, smaller, larger) or focal_length, to_world;
 *              film width and height; sampler sample_count
 *   integrator max_depth (nested integrators searched): Mitsuba counts the
 *              path's segments from the camera as we do, so the number is
 *              kept; -1 (unbounded, the default) becomes 1024. */
#ifndef SG_MITSUBA_SCENE_H
#define SG_MITSUBA_SCENE_H

#include "error.h"
#include "scene.h"

/* Loads a Mitsuba XML file. Malformed or meaningless input (no light, a
 * missing mesh, an unknown reference, a cyclic include, a cut file) fails
 * with "file:line: cause"; what is understood but not supported becomes
 * one scene warning per kind. */
SgScene *sg_mitsuba_scene_load(const char *path, SgError *err);

#endif
