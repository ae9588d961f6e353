// A run's debris as one glTF 2.0 binary (.glb): each fragment meshed once, animated by its pose.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace spall {

struct GltfExportReport {
    int frames = 0;
    int nodes = 0;           ///< one per fragment that ever existed
    int charges = 0;         ///< nodes `charge_<i>` without a mesh, from OUTDIR/scene.json
    int meshes = 0;          ///< distinct pieces (fragments of equal mesh_key share one)
    int64_t triangles = 0;   ///< over the distinct meshes
    int64_t keyframes = 0;   ///< pose samples kept (a resting body's repeats are dropped)
    size_t bytes = 0;        ///< of the .glb
};

/// Reads OUTDIR's level-set frames and writes `glbPath` (under a temporary name, then renamed):
/// - per distinct mesh_key and material, the fragment's level set meshed by OpenVDB's
///   volume-to-mesh (exactly, or adaptively within output.gltf_max_triangles_per_piece of the run's
///   scene.json), in the body's frame with the pivot at its centre of mass, as up to three
///   primitives in the scene material's looks: `<material>` (the object's own surface),
///   `<material> interior` and `<material> joint` (faces whose links broke, through the material
///   or along a masonry joint, from fracture_faces_<id>); no normals, so readers shade it flat;
/// - per fragment, a node `fragment_<id>` whose translation and rotation are sampled at every frame
///   it lives (LINEAR), with scale 1 while it lives and 0 before and after (STEP);
/// - per charge in OUTDIR/scene.json, a node `charge_<i>` without a mesh, extras `tnt_kg`;
/// - metres, converted from spall's Z-up to glTF's Y-up: (x, y, z) -> (x, z, -y).
/// Throws InputError (no frames, fog frames) or IoError. `onFrame(done, total)` reports progress.
GltfExportReport exportGltf(const std::string& outputDirectory, const std::string& glbPath,
                            const std::function<void(int, int)>& onFrame = {});

}  // namespace spall
