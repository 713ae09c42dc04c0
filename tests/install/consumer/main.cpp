// Two in-memory solid box trees in a World: overlapping ones collide, apart
// ones don't. Returns nonzero on any surprise.
#include <cstdio>
#include <octbake.h>

namespace {

octbake::ObjectTree solid_cube(int depth) {
  octbake::OctreeMasks masks;
  masks.bounds = {{-1, -1, -1}, {1, 1, 1}};
  for (int d = 0; d < depth; ++d) masks.masks.emplace_back(size_t(1) << (3 * d), uint8_t{0xFF});
  octbake::TreeInfo info;
  info.name = "cube";
  info.bounds = masks.bounds;
  info.depth = depth;
  return octbake::ObjectTree(std::move(info), std::move(masks));
}

size_t collisions(const octbake::ObjectTree& tree, double gap) {
  octbake::ObjectDesc a, b;
  a.tree = b.tree = &tree;
  b.pose.position = {2 + gap, 0.5, 0};
  octbake::WorldSettings settings;
  settings.response = octbake::Response::none;
  octbake::World world(settings, {a, b});
  std::vector<octbake::Collision> out;
  world.step(out);
  return out.size();
}

}  // namespace

int main() {
  const octbake::ObjectTree tree = solid_cube(/*depth=*/3);
  const size_t overlapping = collisions(tree, -0.1), apart = collisions(tree, 0.1);
  std::printf("overlapping: %zu collision(s), apart: %zu\n", overlapping, apart);
  return overlapping == 1 && apart == 0 ? 0 : 1;
}
