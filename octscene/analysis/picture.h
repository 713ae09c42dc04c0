// `octscene picture ...`: PNG pictures of ObjectTrees and scene frames.
// Parses its own arguments (argv[0] == "picture"); returns the exit status.
#pragma once
#include <span>
#include <string>
#include <vector>

#include "octbake/baker.h"  // Mesh
#include "octbake/object_tree.h"
#include "raster.h"
#include "scene.h"

namespace octbake::scene {

int picture_main(int argc, char** argv);

// The pictures as library calls (tests use them).
enum class TreeView { iso, front, side, top };

// `tree`'s occupied boxes at `depth` as wireframe (faint where hidden) over
// `mesh` (may be null: boxes only), in the tree's local frame, size x size.
Raster render_tree(const ObjectTree& tree, const Mesh* mesh, int depth, int size, TreeView view);
// One render_tree panel per depth, in rows of at most 4.
Raster render_tree_grid(const ObjectTree& tree, const Mesh* mesh, std::span<const int> depths, int size,
                        TreeView view);

// Colour of objects tested at `depth` in scene pictures (and their legend).
Rgb depth_color(int depth);

// The scene from scene.camera (render_scene ignores camera_path: give it the
// frame's camera_on_path()), width x (width * viewport aspect): each object's
// mesh at `poses[i]` tinted by depth_color(depths[i]), with a legend. Where
// meshes[i] is null the object's tree boxes at its depth are drawn instead.
Raster render_scene(const Scene& scene, std::span<const Pose> poses, std::span<const int> depths,
                    std::span<const Mesh* const> meshes, std::span<const ObjectTree* const> trees,
                    const std::string& title, int width);

}  // namespace octbake::scene
