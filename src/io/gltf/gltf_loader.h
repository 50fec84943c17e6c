// glTF 2.0 scenes (.gltf with .bin and image files, or .glb) through tinygltf.
//
// Instancing: each glTF mesh used by a node becomes one Ferry object (one
// Ferry mesh per triangle primitive), and every node that uses it one
// instance with the node's world transform; EXT_mesh_gpu_instancing adds one
// instance per entry of its TRANSLATION / ROTATION / SCALE accessors.
//
// Materials (metallic-roughness): baseColorFactor and baseColorTexture
// (8-bit sRGB, sampler wrap mode), metallicFactor and roughnessFactor times
// the mean of the metallicRoughness texture's B and G channels (Ferry's
// metallic and roughness are not textured). Metallic >= 0.5 is a conductor;
// any other material has glTF's dielectric specular layer over its diffuse
// base: Ferry's layered coat (Material::Coat::Layered) with the material's
// roughness, its Fresnel term from the ior (F0 0.04 at 1.5), tinted by
// KHR_materials_specular; KHR_materials_clearcoat is mixed into that one
// coat (io/gltf/gltf_specular_layers.h has the mapping and what it approximates).
// KHR_materials_ior (0 or at least 1) refracts and sets the coat's Fresnel
// term; KHR_materials_transmission is Material::transmission (a dielectric
// from 0.5). Textures on these factors (transmission R, specular A,
// specularColor RGB in sRGB, clearcoat R, clearcoatRoughness G) are
// averaged into them, as the metallicRoughness texture is;
// clearcoatNormalTexture is ignored. normalTexture is Material::normalTexture
// (texels kept linear: not sRGB colour) with its scale. Every extension value
// is checked (type, range, finite as a float; io/gltf/gltf_material_values.h):
// a wrong one is an InputError naming the file and the material.
// Alpha: MASK and BLEND are both cut-outs (at alphaCutoff, 0.5 for BLEND)
// from the base colour texture's alpha times the factor's. Emission:
// emissiveFactor times KHR_materials_emissive_strength, from the front only
// (glTF culls single-sided back faces) unless the material is doubleSided;
// an emissiveTexture is baked per triangle (the texture averaged at four
// points of each triangle): triangles that emit are split into sub-meshes
// with one material per quantised emission colour (at most 16 levels per
// channel), the rest keep no emission. Occlusion maps and other extensions
// are ignored with one warning each.
// Texture coordinates: a mesh carries one uv set: the TEXCOORD_<n> of its
// material's base colour texture (else of its normal map, else 0), with that
// texture's KHR_texture_transform (offset, rotation, scale, texCoord)
// applied; a normal map on another set or transform is looked up with
// these (a warning). The emissive texture is baked with its own set and
// transform. glTF's v runs down the image, Ferry's up: v -> 1 - v after the
// transform.
//
// Lights (KHR_lights_punctual): directional -> sun (irradiance = colour *
// intensity), point and spot -> small emitters (intensity = colour *
// intensity); photometric values are used as they are, as real-time viewers
// do. A file without lights gets the default sun and sky of OBJ files.
// Cameras: a view per node with a camera, named after the camera (or
// "camera<i>" for camera i without a name; "#2", "#3" for further nodes
// using the same camera); perspective yfov; orthographic cameras become
// perspective ones with a warning. Without cameras: the default view
// framing the scene.
//
// Memory: buffers are read once, straight into tinygltf's buffers (a .glb's
// binary chunk too: its JSON is given to tinygltf with the buffer pointing
// at the chunk's bytes in the file); images are decoded only if a material
// uses them, from the buffer or their file. Accessors are checked against
// their buffer views and buffers before reading, indices against the vertex
// count; non-finite positions, normals or texture coordinates are errors.
#pragma once

#include <string>

#include "io/load_options.h"
#include "scene/scene.h"

namespace ferry {

Scene loadGltf(const std::string& path, const LoadOptions& options = {});

}  // namespace ferry
