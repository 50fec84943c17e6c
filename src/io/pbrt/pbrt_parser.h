// pbrt scene files (v3 and v4 syntax) to a Ferry Scene: the directives, the
// graphics state, and scene building. Materials and textures are mapped in
// pbrt_materials, spectra in pbrt_spectra, non-triangle shapes in
// shape_tessellation, PLY files in ply_reader.
//
// Instancing stays instancing: every ObjectBegin/ObjectEnd becomes one Ferry
// object (its shapes baked with the transform active inside the definition,
// as pbrt does), every ObjectInstance one instance. A top-level shape becomes
// an object with one instance carrying the current transform; a PLY file
// used several times at the top level with the same material becomes one
// object with several instances.
//
// Supported: Include and Import (relative to the main file's directory, then
// the including file's), AttributeBegin/End, TransformBegin/End,
// ObjectBegin/End/Instance, Identity, Translate, Rotate, Scale, LookAt,
// ConcatTransform, Transform, CoordinateSystem, CoordSysTransform,
// ReverseOrientation, ActiveTransform (only the start transform is used),
// v4's Attribute (per-target default parameters), WorldBegin/WorldEnd,
// Camera "perspective", Film, Texture, Material, MakeNamedMaterial,
// NamedMaterial, LightSource, AreaLightSource "diffuse", Shape.
// Shapes: trianglemesh, plymesh, bilinearmesh, loopsubdiv, curves, sphere,
// disk, cylinder, heightfield; `alpha` on any of them.
// Lights: infinite (constant and image, lat-long as in v3 or equal-area
// square as in v4, resampled to Ferry's y-up lat-long whatever the light's
// transform), distant (a sun), point and spot (small emitters: a sphere, and
// a disk at the bottom of a black tube whose opening matches the cone),
// goniometric and projection (as point lights), area lights (emission on the
// shapes' materials; Ferry's emitters are two-sided).
// Skipped with one warning each: Sampler, Integrator, PixelFilter,
// Accelerator, media, Option, ColorSpace, TransformTimes, unsupported
// shapes, lights and camera types, and every parameter nothing reads.
// Errors (InputError at file:line:column): lexical errors, unknown
// directives, wrong argument counts or types, unbalanced blocks, include
// loops, missing files, unknown named materials, objects or coordinate
// systems, out-of-range indices, non-finite numbers, singular transforms.
//
// The camera: pbrt's is left-handed, which CameraView::leftHanded records
// (the image is mirrored otherwise). pbrt's fov is that of the image's
// shorter side; it is converted to Ferry's vertical fov with the Film's
// aspect ratio. The Film's resolution and file name become the scene's
// filmWidth, filmHeight and filmFilename.
#pragma once

#include <string>
#include <string_view>

#include "io/load_options.h"
#include "scene/scene.h"

namespace ferry {

Scene loadPbrt(const std::string& path, const LoadOptions& options = {});
// The same from text in memory (tests, fuzzers); relative file names resolve
// against `directory`. `name` is used in messages.
Scene loadPbrtFromString(std::string_view text, const std::string& name,
                         const std::string& directory, const LoadOptions& options = {});

}  // namespace ferry
