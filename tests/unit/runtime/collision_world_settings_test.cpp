// Settings: CollisionWorld::validate / make refuse bad settings with a typed
// error naming the setting, where the constructor (the lenient form) replaces
// or clamps them.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "octbake/collision_world.h"

namespace octbake {
namespace {

void expect_refused(const std::function<void(CollisionSettings&)>& spoil, const std::string& names) {
  CollisionSettings s;
  spoil(s);
  const Status st = CollisionWorld::validate(s);
  ASSERT_FALSE(st.ok()) << names;
  EXPECT_EQ(st.error().code, ErrorCode::invalid_argument) << names;
  EXPECT_NE(st.error().message.find(names), std::string::npos) << st.error().message;
  Result<std::unique_ptr<CollisionWorld>> w = CollisionWorld::make(s);
  ASSERT_FALSE(w.ok()) << names;
  EXPECT_EQ(w.error().message, st.error().message);
  // The lenient constructor still accepts them.
  CollisionWorld lenient(s);
  EXPECT_EQ(lenient.size(), 0u);
}

TEST(CollisionWorldSettings, DefaultsAndGoodSettingsAreAccepted) {
  EXPECT_TRUE(CollisionWorld::validate(CollisionSettings{}).ok());
  CollisionSettings s;
  s.bounds = {Eigen::Vector3d(1e7, 1e7, 1e7), Eigen::Vector3d(1e7 + 1, 1e7 + 2, 1e7 + 3)};
  s.world_depth = 10;
  s.threads = 3;
  s.lod.min_depth = s.lod.max_depth = 0;
  Result<std::unique_ptr<CollisionWorld>> w = CollisionWorld::make(s);
  ASSERT_TRUE(w.ok()) << w.error().message;
  EXPECT_EQ((*w)->settings().world_depth, 10);
  EXPECT_EQ((*w)->world_tree().bounds().max, s.bounds.max);
  s.world_depth = 0;
  EXPECT_TRUE(CollisionWorld::validate(s).ok());
}

TEST(CollisionWorldSettings, EachBadSettingIsRefusedByName) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  expect_refused([&](CollisionSettings& s) { s.bounds.min.x() = nan; }, "settings.bounds");
  expect_refused([&](CollisionSettings& s) { s.bounds.max.z() = inf; }, "settings.bounds");
  expect_refused([&](CollisionSettings& s) { s.bounds.min.y() = -inf; }, "settings.bounds");
  expect_refused([](CollisionSettings& s) { s.bounds.max.y() = s.bounds.min.y(); }, "settings.bounds");  // flat
  expect_refused([](CollisionSettings& s) { std::swap(s.bounds.min, s.bounds.max); }, "settings.bounds");
  expect_refused([](CollisionSettings& s) { s.world_depth = -1; }, "settings.world_depth");
  expect_refused([](CollisionSettings& s) { s.world_depth = 11; }, "settings.world_depth");
  expect_refused([](CollisionSettings& s) { s.threads = 0; }, "settings.threads");
  expect_refused([](CollisionSettings& s) { s.threads = -4; }, "settings.threads");
  expect_refused([](CollisionSettings& s) { s.lod.min_depth = -1; }, "settings.lod");
  expect_refused([](CollisionSettings& s) { s.lod.min_depth = 5, s.lod.max_depth = 4; }, "settings.lod");
  expect_refused([](CollisionSettings& s) { s.lod.pixel_tolerance = 0; }, "settings.lod: pixel_tolerance");
  expect_refused([&](CollisionSettings& s) { s.lod.pixel_tolerance = nan; }, "settings.lod: pixel_tolerance");
}

// The lenient constructor as before: a bad box becomes the default one, the
// depth is clamped.
TEST(CollisionWorldSettings, ConstructorStillReplacesAndClamps) {
  CollisionSettings s;
  s.bounds.max.x() = s.bounds.min.x();
  s.world_depth = 42;
  CollisionWorld w(s);
  EXPECT_EQ(w.world_tree().bounds().min, CollisionSettings{}.bounds.min);
  EXPECT_EQ(w.world_tree().bounds().max, CollisionSettings{}.bounds.max);
  EXPECT_EQ(w.settings().world_depth, 10);
}

}  // namespace
}  // namespace octbake
