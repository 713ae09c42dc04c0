// libFuzzer target: parse_scene() must reject or accept any bytes without
// crashing, and what it accepts must survive write_scene() -> parse_scene().
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace octbake::scene;
  const std::string text(reinterpret_cast<const char*>(data), size);
  octbake::Result<Scene> scene = parse_scene(text, "dir");
  if (!scene) {
    if (scene.error().message.empty()) std::abort();  // every refusal says why
    return 0;
  }
  // Accepted scenes obey the file's rules.
  for (const SceneObject& o : scene->objects)
    if (!(o.pose.scale > 0) || !o.pose.position.allFinite() || std::abs(o.pose.rotation.norm() - 1) > 1e-9)
      std::abort();
  octbake::Result<Scene> again = parse_scene(write_scene(*scene, "baked"), "dir");
  if (!again || again->objects.size() != scene->objects.size() || again->frames != scene->frames)
    std::abort();
  return 0;
}
