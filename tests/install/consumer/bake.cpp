// Bakes a tetrahedron in process through the installed octbake::baker and
// reads it back with the runtime. Returns nonzero on any surprise.
#include <cstdio>
#include <octbake.h>
#include <octbake/baker.h>

int main() {
  const double vertices[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const uint32_t indices[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  octbake::BakeOptions options;
  options.depth = 3;
  auto bytes = octbake::bake_to_memory(vertices, indices, "tetra", options);
  if (!bytes) return std::fprintf(stderr, "%s\n", bytes.error().message.c_str()), 1;
  auto file = octbake::BakedFile::from_bytes(*bytes, "memory");
  if (!file) return std::fprintf(stderr, "%s\n", file.error().message.c_str()), 1;
  auto tree = file->load(0, 3);
  if (!tree) return 1;
  std::printf("tetra: %llu boxes at depth 3\n", static_cast<unsigned long long>(tree->box_count(3)));
  return tree->box_count(3) > 0 && tree->box_count(3) < 512 ? 0 : 1;
}
