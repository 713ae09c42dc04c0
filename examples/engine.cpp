// An engine's frame loop on octbake's CollisionWorld.
//
// The engine owns everything that moves: its entities' transforms, their
// velocities and spin, the camera. Each frame it spawns and despawns
// entities, integrates its own transforms, hands the poses and the camera to
// the collision world, reads the contacts and answers them (pushes the two
// entities apart along the contact's separating direction and reflects their
// velocities), then casts one ray from the camera ("what is under the
// crosshair?").
//
//   example_engine BAKED_DIR     (car.oct, human.oct, tree.oct from octbake)
//
// It checks what an engine relies on and exits non-zero when any fails:
// contacts only name live entities, despawned handles are refused, the run is
// bit-identical when repeated and with 1 or 3 threads, and there are contacts
// and ray hits at all.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "octbake.h"

namespace {

using namespace octbake;

int g_failures = 0;
#define CHECK(cond)                                                  \
  do {                                                               \
    if (!(cond)) {                                                   \
      std::fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      ++g_failures;                                                  \
    }                                                                \
  } while (0)

// The engine's own entity: transform, motion, and the collision handle.
struct Entity {
  Eigen::Vector3d position{0, 0, 0}, velocity{0, 0, 0};
  Eigen::Vector3d spin_axis{0, 1, 0};
  double angle = 0, spin = 0;  // rad, rad/s
  double scale = 1;
  int model = 0;
  ObjectHandle handle;
  bool alive = false;
};

struct Summary {
  uint64_t contacts = 0, ray_hits = 0, spawned = 0, despawned = 0, hash = 1469598103934665603ull;
  void mix(double v) {
    unsigned char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    for (unsigned char c : b) hash = (hash ^ c) * 1099511628211ull;
  }
};

constexpr double kDt = 1.0 / 60.0;
constexpr double kArena = 12;  // entities bounce inside [-kArena, kArena]^3

Pose pose_of(const Entity& e) {
  Pose p;
  p.position = e.position;
  p.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(e.angle, e.spin_axis));
  p.scale = e.scale;
  return p;
}

Summary run(const std::vector<ObjectTree>& models, int threads, int frames) {
  CollisionSettings settings;
  settings.bounds = {Eigen::Vector3d::Constant(-kArena), Eigen::Vector3d::Constant(kArena)};
  settings.world_depth = 3;
  settings.lod.policy = LodPolicy::screen;
  settings.lod.pixel_tolerance = 2;
  settings.threads = threads;
  CollisionWorld world(settings);

  std::mt19937 rng(2026);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * (rng() / 4294967296.0); };
  std::vector<Entity> entities;
  std::vector<ObjectHandle> despawned;
  std::vector<Contact> contacts;
  Summary summary;

  for (int frame = 0; frame < frames; ++frame) {
    // Spawn one entity every 4 frames, despawn a random one every 9.
    if (frame % 4 == 0) {
      Entity e;
      e.model = int(rng() % models.size());
      e.position = {uniform(-8, 8), uniform(-8, 8), uniform(-8, 8)};
      e.velocity = {uniform(-3, 3), uniform(-3, 3), uniform(-3, 3)};
      e.spin_axis = Eigen::Vector3d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized();
      e.spin = uniform(-2, 2);
      e.scale = 2.0 / models[e.model].bounds().max.cwiseAbs().maxCoeff() * uniform(0.6, 1.2);
      Result<ObjectHandle> h = world.create(TreeSource::fixed(&models[e.model]), pose_of(e));
      CHECK(h.ok());
      e.handle = *h;
      e.alive = true;
      entities.push_back(e);
      ++summary.spawned;
    }
    if (frame % 9 == 0 && !entities.empty()) {
      const size_t i = rng() % entities.size();
      CHECK(world.destroy(entities[i].handle).ok());
      despawned.push_back(entities[i].handle);
      entities.erase(entities.begin() + ptrdiff_t(i));
      ++summary.despawned;
    }

    // The engine's own integration, then the poses go to the collision world.
    for (Entity& e : entities) {
      e.position += e.velocity * kDt;
      e.angle += e.spin * kDt;
      for (int k = 0; k < 3; ++k)
        if (std::abs(e.position[k]) > kArena && e.position[k] * e.velocity[k] > 0) e.velocity[k] = -e.velocity[k];
      CHECK(world.set_pose(e.handle, pose_of(e)).ok());
    }

    // A camera orbiting the arena, every frame.
    Camera camera;
    const double a = 0.01 * frame;
    camera.position = {30 * std::cos(a), 8, 30 * std::sin(a)};
    camera.look_at = {0, 0, 0};
    world.set_camera(camera);

    // Contacts, answered by the engine.
    const DetectStats stats = world.detect(contacts);
    summary.contacts += stats.contacts;
    auto find = [&](ObjectHandle h) -> Entity* {
      for (Entity& e : entities)
        if (e.handle == h) return &e;
      return nullptr;
    };
    for (const Contact& c : contacts) {
      Entity* ea = find(c.a);
      Entity* eb = find(c.b);
      CHECK(ea && eb);  // contacts only name live entities
      if (!ea || !eb) continue;
      const Eigen::Vector3d& n = c.estimate.normal;  // from a towards b
      const double push = 0.5 * c.estimate.penetration;
      ea->position -= n * push;
      eb->position += n * push;
      const double closing = (eb->velocity - ea->velocity).dot(n);
      if (closing < 0) {  // approaching along n: exchange that component
        ea->velocity += n * closing;
        eb->velocity -= n * closing;
      }
      summary.mix(c.estimate.penetration);
    }

    // One ray per frame: what the camera looks at.
    Result<std::optional<RayHit>> hit = world.ray_cast(camera.position, camera.look_at - camera.position, 100.0);
    CHECK(hit.ok());
    if (hit.ok() && hit->has_value()) {
      ++summary.ray_hits;
      CHECK(find((*hit)->object) != nullptr);
      CHECK((*hit)->distance > 0 && (*hit)->distance < 100);
      summary.mix((*hit)->distance);
    }
  }

  // Despawned handles are refused, never reused silently.
  for (ObjectHandle h : despawned) {
    CHECK(!world.alive(h));
    CHECK(!world.set_pose(h, Pose{}).ok());
  }
  for (const Entity& e : entities) {
    summary.mix(e.position.x()), summary.mix(e.position.y()), summary.mix(e.position.z());
    CHECK(world.alive(e.handle));
  }
  return summary;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: example_engine BAKED_DIR\n");
    return 2;
  }
  Result<ModelLibrary> library = ModelLibrary::open(argv[1]);
  if (!library) {
    std::fprintf(stderr, "%s\n", library.error().message.c_str());
    return 1;
  }
  std::vector<ObjectTree> models;
  for (const char* name : {"car", "human", "tree"}) {
    Result<ObjectTree> tree = library->load(name, 12);
    if (!tree) {
      std::fprintf(stderr, "%s: %s\n", name, tree.error().message.c_str());
      return 1;
    }
    models.push_back(std::move(tree).value());
  }

  const Summary one = run(models, 1, 600);
  const Summary again = run(models, 1, 600);
  const Summary threaded = run(models, 3, 600);
  CHECK(one.contacts > 0);
  CHECK(one.ray_hits > 0);
  CHECK(one.hash == again.hash && one.contacts == again.contacts);          // bit-identical repeat
  CHECK(one.hash == threaded.hash && one.contacts == threaded.contacts);    // and with 3 threads
  std::printf("600 frames: %llu spawned, %llu despawned, %llu contacts answered, %llu ray hits; hash %016llx\n",
              (unsigned long long)one.spawned, (unsigned long long)one.despawned, (unsigned long long)one.contacts,
              (unsigned long long)one.ray_hits, (unsigned long long)one.hash);
  if (g_failures) std::fprintf(stderr, "%d checks failed\n", g_failures);
  return g_failures == 0 ? 0 : 1;
}
