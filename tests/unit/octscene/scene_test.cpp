// parse_scene: every class of bad scene gives its own error naming the JSON
// path; a good scene reads back exactly what write_scene wrote.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <random>

#include "scene.h"

namespace octbake::scene {
namespace {

using nlohmann::json;

json good_scene() {
  return json::parse(R"({
    "format": "octbake-scene/1",
    "baked": "baked",
    "camera": {"position": [0, 10, -60], "look_at": [0, 0, 0], "up": [0, 1, 0],
               "fov_y_deg": 60, "viewport": [1920, 1080], "near": 0.1, "far": 2000},
    "world": {"min": [-100, -100, -100], "max": [100, 100, 100], "depth": 4},
    "timestep": 0.0333333333,
    "frames": 7200,
    "objects": [
      {"name": "tree_0", "model": "tree", "position": [1.5, 0, 3],
       "rotation": [0, 0, 0, 1], "scale": 1.0, "velocity": [0, 0, 0]},
      {"name": "car_0", "model": "car", "position": [10, 0, 3]}
    ]})");
}

// The error message of parsing `text`, or "" when it parses.
std::string error_of(const std::string& text) {
  Result<Scene> s = parse_scene(text, "scenes");
  return s ? std::string() : s.error().message;
}
std::string error_of(const json& j) { return error_of(j.dump()); }

TEST(Scene, GoodSceneParses) {
  Result<Scene> s = parse_scene(good_scene().dump(), "scenes");
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->baked, "scenes/baked");
  EXPECT_EQ(s->frames, 7200);
  EXPECT_EQ(s->world_depth, 4);
  EXPECT_EQ(s->camera.viewport_w, 1920);
  EXPECT_EQ(s->camera.viewport_h, 1080);
  ASSERT_EQ(s->objects.size(), 2u);
  EXPECT_EQ(s->objects[1].name, "car_0");
  EXPECT_EQ(s->objects[1].model, "car");
  EXPECT_EQ(s->objects[1].pose.scale, 1.0);  // defaults
  EXPECT_TRUE(s->objects[1].pose.rotation.coeffs().isApprox(Eigen::Quaterniond::Identity().coeffs()));
  EXPECT_TRUE(s->objects[1].velocity.isZero(0));
  EXPECT_EQ(s->objects[0].pose.position, Eigen::Vector3d(1.5, 0, 3));
}

TEST(Scene, QuaternionOrderIsXyzw) {
  json j = good_scene();
  const double h = std::sqrt(0.5);
  j["objects"][0]["rotation"] = {0, h, 0, h};  // 90 degrees about y
  Result<Scene> s = parse_scene(j.dump(), "");
  ASSERT_TRUE(s) << s.error().message;
  Eigen::Vector3d x = s->objects[0].pose.rotation * Eigen::Vector3d(1, 0, 0);
  EXPECT_TRUE(x.isApprox(Eigen::Vector3d(0, 0, -1), 1e-12)) << x.transpose();
}

TEST(Scene, UnknownKeyAtEveryLevel) {
  for (const char* where : {"", "camera", "world", "objects"}) {
    json j = good_scene();
    json& target = std::string(where) == "" ? j : std::string(where) == "objects" ? j["objects"][1] : j[where];
    target["colour"] = 1;
    std::string expected = std::string(where) == ""          ? "colour: unknown key"
                           : std::string(where) == "objects" ? "objects[1].colour: unknown key"
                                                             : std::string(where) + ".colour: unknown key";
    EXPECT_EQ(error_of(j), expected);
  }
}

TEST(Scene, MissingRequiredKeys) {
  struct Case {
    std::vector<std::string> path;
    const char* message;
  };
  for (const Case& c : std::vector<Case>{
           {{"format"}, "format: missing required key"},
           {{"camera"}, "camera: missing required key"},
           {{"camera", "look_at"}, "camera.look_at: missing required key"},
           {{"world", "min"}, "world.min: missing required key"},
           {{"timestep"}, "timestep: missing required key"},
           {{"frames"}, "frames: missing required key"},
           {{"objects"}, "objects: missing required key"},
           {{"objects", "0", "model"}, "objects[0].model: missing required key"},
           {{"objects", "1", "position"}, "objects[1].position: missing required key"},
       }) {
    json j = good_scene();
    json* parent = &j;
    for (size_t i = 0; i + 1 < c.path.size(); ++i)
      parent = parent->is_array() ? &(*parent)[std::stoul(c.path[i])] : &(*parent)[c.path[i]];
    parent->erase(c.path.back());
    EXPECT_EQ(error_of(j), c.message);
  }
}

TEST(Scene, WrongTypes) {
  json j = good_scene();
  j["camera"]["fov_y_deg"] = "wide";
  EXPECT_EQ(error_of(j), "camera.fov_y_deg: expected a number, got string");
  j = good_scene();
  j["objects"][0]["position"] = {1, 2};
  EXPECT_EQ(error_of(j), "objects[0].position: expected an array of 3 numbers");
  j = good_scene();
  j["objects"][1]["velocity"] = {1, true, 3};
  EXPECT_EQ(error_of(j), "objects[1].velocity[1]: expected a number, got boolean");
  j = good_scene();
  j["frames"] = 10.5;
  EXPECT_EQ(error_of(j), "frames: expected an integer, got number");
  j = good_scene();
  j["objects"] = json::object();
  EXPECT_EQ(error_of(j), "objects: expected an array, got object");
  j = good_scene();
  j["objects"][0]["name"] = 7;
  EXPECT_EQ(error_of(j), "objects[0].name: expected a string, got number");
  j = good_scene();
  j["world"] = json::array();
  EXPECT_EQ(error_of(j), "world: expected an object, got array");
  EXPECT_EQ(error_of(std::string("[1, 2]")), "(root): expected an object, got array");
}

TEST(Scene, NonFiniteNumbers) {
  // 1e999 overflows to infinity when read; JSON has no NaN literal at all.
  for (const char* literal : {"1e999", "-1e999"}) {
    json j = good_scene();
    j["objects"][1]["scale"] = 12345.25;
    std::string text = j.dump();
    text.replace(text.find("12345.25"), 8, literal);
    EXPECT_EQ(error_of(text), "objects[1].scale: not a finite number");
    j = good_scene();
    j["camera"]["position"][2] = 12345.25;
    text = j.dump();
    text.replace(text.find("12345.25"), 8, literal);
    EXPECT_EQ(error_of(text), "camera.position[2]: not a finite number");
  }
  std::string text = good_scene().dump();
  text.replace(text.find("0.0333333333"), 12, "NaN");
  EXPECT_EQ(error_of(text).rfind("invalid JSON at line 1, column ", 0), 0u) << error_of(text);
}

TEST(Scene, RangeChecks) {
  struct Case {
    std::function<void(json&)> edit;
    const char* message;
  };
  for (const Case& c : std::vector<Case>{
           {[](json& j) { j["format"] = "octbake-scene/2"; },
            "format: expected \"octbake-scene/1\", got \"octbake-scene/2\""},
           {[](json& j) { j["camera"]["fov_y_deg"] = 180; }, "camera.fov_y_deg: must be in (0, 180)"},
           {[](json& j) { j["camera"]["fov_y_deg"] = 0; }, "camera.fov_y_deg: must be in (0, 180)"},
           {[](json& j) { j["camera"]["viewport"] = {1920, 0}; }, "camera.viewport[1]: must be in 1..1048576"},
           {[](json& j) { j["camera"]["viewport"] = {1920.5, 10}; },
            "camera.viewport[0]: expected an integer, got number"},
           {[](json& j) { j["camera"]["near"] = 0; }, "camera.near: must be > 0"},
           {[](json& j) { j["camera"]["far"] = 0.05; }, "camera.far: must be > near"},
           {[](json& j) { j["camera"]["look_at"] = {0, 10, -60}; }, "camera.look_at: same as position"},
           {[](json& j) {
              j["camera"]["position"] = {-1e308, 10, -60};
              j["camera"]["look_at"] = {1e308, 0, 0};
            },
            "camera.look_at: too far from position (their difference overflows a double)"},
           {[](json& j) { j["world"]["max"][1] = -100; }, "world.max: must be > world.min on every axis"},
           {[](json& j) { j["world"]["depth"] = 11; }, "world.depth: must be in 0..10"},
           {[](json& j) { j["timestep"] = 0; }, "timestep: must be > 0"},
           {[](json& j) { j["frames"] = -1; }, "frames: must be in 0..100000000"},
           {[](json& j) { j["frames"] = int64_t{1} << 32; }, "frames: must be in 0..100000000"},
           {[](json& j) { j["objects"][1]["scale"] = 0; }, "objects[1].scale: must be > 0"},
           {[](json& j) { j["objects"][1]["scale"] = -2; }, "objects[1].scale: must be > 0"},
           {[](json& j) { j["objects"][0]["rotation"] = {0, 0, 0, 1.00001}; },
            "objects[0].rotation: not a unit quaternion"},
           {[](json& j) { j["objects"][0]["rotation"] = {0, 0, 0, 0}; },
            "objects[0].rotation: not a unit quaternion"},
           {[](json& j) { j["objects"][1]["name"] = "tree_0"; }, "objects[1].name: duplicate name \"tree_0\""},
           {[](json& j) { j["objects"][1]["name"] = "a,b"; },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["name"] = "a\"b"; },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["name"] = "a\nb"; },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["name"] = "a\rb"; },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["name"] = std::string("a\0b", 3); },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["name"] = "a\tb"; },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["name"] = "a\x7f" "b"; },
            "objects[1].name: must not contain a comma, a quote, a line break or another control character"},
           {[](json& j) { j["objects"][1]["model"] = ""; }, "objects[1].model: must not be empty"},
       }) {
    json j = good_scene();
    c.edit(j);
    EXPECT_EQ(error_of(j), c.message);
  }
}

TEST(Scene, RotationToleranceIsOneMillionth) {
  // |q| - 1 within 1e-6 is accepted (and normalised); beyond it is refused.
  json j = good_scene();
  j["objects"][0]["rotation"] = {0, 0, 0, 1 + 0.9e-6};
  Result<Scene> s = parse_scene(j.dump(), "");
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_NEAR(s->objects[0].pose.rotation.norm(), 1.0, 1e-15);
  j["objects"][0]["rotation"] = {0, 0, 0, 1 - 1.1e-6};
  EXPECT_EQ(error_of(j), "objects[0].rotation: not a unit quaternion");
}

TEST(Scene, DuplicateJsonKeys) {
  std::string text = good_scene().dump();
  text.replace(text.find("\"scale\":1.0"), 11, "\"scale\":1.0,\"scale\":2.0");
  EXPECT_EQ(error_of(text), "objects[0].scale: duplicate key");
}

// The path of an error found while reading the text counts every object and
// array element before it, also far into a large scene, and a good large
// scene reads back whole.
TEST(Scene, ErrorPathsFarIntoALargeScene) {
  json j = good_scene();
  json& objects = j["objects"];
  const json car = objects[1];
  for (int i = 2; i < 5000; ++i) {
    objects.push_back(car);
    objects.back()["name"] = "car_" + std::to_string(i);
  }
  Result<Scene> s = parse_scene(j.dump(), "");
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->objects.size(), 5000u);
  EXPECT_EQ(s->objects[4321].name, "car_4321");
  objects[4321]["scale"] = 12345.25;
  objects[4321]["velocity"] = {0, 0, 0};
  std::string text = j.dump();
  const size_t at = text.find("12345.25");
  EXPECT_EQ(error_of(std::string(text).replace(at, 8, "1e999")), "objects[4321].scale: not a finite number");
  text.replace(at, 8, "2,\"velocity\":[1,2,3],\"scale\":3");
  EXPECT_EQ(error_of(text), "objects[4321].scale: duplicate key");
  text = j.dump();
  const size_t v = text.find("[0,0,0]", text.find("12345.25"));
  EXPECT_EQ(error_of(text.replace(v, 7, "[0,0,-1e999]")), "objects[4321].velocity[2]: not a finite number");
}

// The objects are converted as the reader meets them (no document of them is
// kept), yet the errors are those of a whole-document check: the other keys'
// first, wherever they sit in the text, then the first bad object; elements
// that are not objects, and "objects" keys deeper down, are no exception.
TEST(Scene, ObjectsReadAsTheyComeReportTheSameErrors) {
  json j = good_scene();
  j["objects"][1]["scale"] = -1;
  EXPECT_EQ(error_of(j), "objects[1].scale: must be > 0");
  std::string text = j.dump();  // keys sorted: "timestep" comes after "objects"
  ASSERT_LT(text.find("\"objects\""), text.find("\"timestep\""));
  j["timestep"] = 0;
  EXPECT_EQ(error_of(j), "timestep: must be > 0");
  j = good_scene();
  j["objects"].push_back(5);
  j["objects"].push_back(json::array({1, 2}));
  EXPECT_EQ(error_of(j), "objects[2]: expected an object, got number");
  j = good_scene();
  j["objects"].push_back(j["objects"][0]);
  EXPECT_EQ(error_of(j), "objects[2].name: duplicate name \"tree_0\"");
  j = good_scene();
  j["objects"] = json::array({json::object({{"objects", json::array({1})}})});
  EXPECT_EQ(error_of(j), "objects[0].objects: unknown key");
  j["objects"] = json::object({{"a", 1}});
  EXPECT_EQ(error_of(j), "objects: expected an array, got object");
  j.erase("objects");
  EXPECT_EQ(error_of(j), "objects: missing required key");
  // And what parses is every object, in order, with its values.
  j = good_scene();
  for (int i = 0; i < 300; ++i)
    j["objects"].push_back({{"name", "o" + std::to_string(i)}, {"model", "m"}, {"position", {i, -i, 0.5 * i}}});
  Result<Scene> s = parse_scene(j.dump(), "");
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->objects.size(), 302u);
  for (int i = 0; i < 300; ++i) {
    EXPECT_EQ(s->objects[size_t(i) + 2].name, "o" + std::to_string(i));
    EXPECT_EQ(s->objects[size_t(i) + 2].pose.position, Eigen::Vector3d(i, -i, 0.5 * i));
  }
}

TEST(Scene, InvalidJsonNamesLineAndColumn) {
  std::string text = "{\n  \"format\": \"octbake-scene/1\",\n  \"frames\": 10,,\n}";
  std::string e = error_of(text);
  EXPECT_EQ(e.rfind("invalid JSON at line 3, column 16: ", 0), 0u) << e;
  EXPECT_EQ(error_of(std::string()).rfind("invalid JSON at line 1, column 1: ", 0), 0u) << error_of(std::string());
}

TEST(Scene, AbsoluteBakedPathIsKept) {
  json j = good_scene();
  j["baked"] = "/data/baked";
  Result<Scene> s = parse_scene(j.dump(), "scenes");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->baked, "/data/baked");
}

// Random scenes survive write_scene -> parse_scene bit for bit.
TEST(Scene, WriteParseRoundTripIsExact) {
  std::mt19937 rng(12345);
  auto real = [&](double lo, double hi) { return lo + (hi - lo) * (rng() * 0x1p-32); };
  for (int round = 0; round < 50; ++round) {
    Scene s;
    s.world = {{-real(1, 1e6), -real(1, 1e6), -real(1, 1e6)}, {real(1, 1e6), real(1, 1e6), real(1, 1e6)}};
    s.world_depth = static_cast<int>(rng() % 11);
    s.timestep = real(1e-6, 1);
    s.frames = rng() % 100000;
    s.camera.position = {real(-9, 9), real(-9, 9), real(-9, 9)};
    s.camera.fov_y_deg = real(1, 179);
    const int n = static_cast<int>(rng() % 20);
    for (int i = 0; i < n; ++i) {
      SceneObject o;
      o.name = "obj_" + std::to_string(i);
      o.model = "m" + std::to_string(rng() % 3);
      o.pose.position = {real(-1e5, 1e5), real(-1e-3, 1e-3), real(-7, 7)};
      o.pose.rotation = Eigen::Quaterniond(real(-1, 1), real(-1, 1), real(-1, 1), real(-1, 1)).normalized();
      o.pose.scale = real(1e-3, 1e3);
      o.velocity = {real(-5, 5), 0, real(-1e-9, 1e-9)};
      s.objects.push_back(o);
    }
    Result<Scene> back = parse_scene(write_scene(s, "b"), "");
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_EQ(back->baked, "b");
    EXPECT_EQ(back->world, s.world);
    EXPECT_EQ(back->world_depth, s.world_depth);
    EXPECT_EQ(back->timestep, s.timestep);
    EXPECT_EQ(back->frames, s.frames);
    EXPECT_EQ(back->camera.position, s.camera.position);
    EXPECT_EQ(back->camera.fov_y_deg, s.camera.fov_y_deg);
    ASSERT_EQ(back->objects.size(), s.objects.size());
    for (size_t i = 0; i < s.objects.size(); ++i) {
      EXPECT_EQ(back->objects[i].name, s.objects[i].name);
      EXPECT_EQ(back->objects[i].model, s.objects[i].model);
      EXPECT_EQ(back->objects[i].pose.position, s.objects[i].pose.position);
      EXPECT_EQ(back->objects[i].pose.scale, s.objects[i].pose.scale);
      EXPECT_EQ(back->objects[i].velocity, s.objects[i].velocity);
      EXPECT_TRUE(back->objects[i].pose.rotation.coeffs().isApprox(s.objects[i].pose.rotation.coeffs(), 1e-15));
    }
  }
}

// ---- motion keys: "angular_velocity" and "camera_path" ----

json moving_camera_scene() {
  json j = good_scene();
  j["objects"][1]["angular_velocity"] = {0, 1.5, -0.25};
  j["camera_path"] = json::parse(R"([
    {"frame": 0, "position": [0, 10, -60], "look_at": [0, 0, 0]},
    {"frame": 100, "position": [30, 5, -20], "look_at": [0, 0, 10]},
    {"frame": 7200, "position": [-5, 2, 40], "look_at": [0, 0, 0]}])");
  return j;
}

// A camera 1e200 from what it looks at, or 1e-300, still looks (|d|^2 over-
// or underflows there; the check once called such a camera's up "zero or
// parallel to the view direction"), and so does a path between such keys.
TEST(SceneMotion, FarAndNearCamerasStillLook) {
  for (const double d : {1e200, 1e300, 1e-300}) {
    json j = moving_camera_scene();
    j["camera"]["position"] = {0, 0.5 * d, -d};
    j["camera"]["look_at"] = {0, 0, 0};
    j["camera_path"][0]["position"] = {d, 0.5 * d, -d};
    j["camera_path"][1]["position"] = {-d, 0.1 * d, 0.2 * d};
    j["camera_path"][1]["look_at"] = {0, 0, 0};
    Result<Scene> s = parse_scene(j.dump(), "");
    EXPECT_TRUE(s) << d << ": " << s.error().message;
  }
}

TEST(SceneMotion, KeysParse) {
  Result<Scene> s = parse_scene(moving_camera_scene().dump(), "");
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_TRUE(s->objects[0].angular_velocity.isZero(0));  // default
  EXPECT_EQ(s->objects[1].angular_velocity, Eigen::Vector3d(0, 1.5, -0.25));
  ASSERT_EQ(s->camera_path.size(), 3u);
  EXPECT_EQ(s->camera_path[1].frame, 100);
  EXPECT_EQ(s->camera_path[1].position, Eigen::Vector3d(30, 5, -20));
  EXPECT_EQ(s->camera_path[1].look_at, Eigen::Vector3d(0, 0, 10));
  EXPECT_EQ(s->camera_path[2].frame, 7200);
  // The base camera keeps its own position; the path only replaces it per frame.
  EXPECT_EQ(s->camera.position, Eigen::Vector3d(0, 10, -60));
  const Camera mid = camera_on_path(s->camera, s->camera_path, 50);
  EXPECT_EQ(mid.position, Eigen::Vector3d(15, 7.5, -40));
  EXPECT_EQ(mid.fov_y_deg, 60);
  Result<Scene> plain = parse_scene(good_scene().dump(), "");
  ASSERT_TRUE(plain);
  EXPECT_TRUE(plain->camera_path.empty());
}

TEST(SceneMotion, BadKeysNameTheirPath) {
  struct Case {
    std::function<void(json&)> edit;
    const char* message;
  };
  for (const Case& c : std::vector<Case>{
           {[](json& j) { j["objects"][1]["angular_velocity"] = {1, 2}; },
            "objects[1].angular_velocity: expected an array of 3 numbers"},
           {[](json& j) { j["objects"][1]["angular_velocity"] = 3; },
            "objects[1].angular_velocity: expected an array of 3 numbers"},
           {[](json& j) { j["objects"][0]["angular_velocity"] = {1, "fast", 0}; },
            "objects[0].angular_velocity[1]: expected a number, got string"},
           {[](json& j) { j["objects"][0]["angular_velocity"] = {1e308, 1e308, 0}; },
            "objects[0].angular_velocity: rate too large"},
           {[](json& j) { j["camera_path"] = json::object(); }, "camera_path: expected an array, got object"},
           {[](json& j) { j["camera_path"][1] = 4; }, "camera_path[1]: expected an object, got number"},
           {[](json& j) { j["camera_path"][2]["frame"] = 100; },
            "camera_path[2].frame: frames must be strictly ascending"},
           {[](json& j) { j["camera_path"][2]["frame"] = 50; },
            "camera_path[2].frame: frames must be strictly ascending"},
           {[](json& j) { j["camera_path"][0]["frame"] = -1; }, "camera_path[0].frame: must be >= 0"},
           {[](json& j) { j["camera_path"][0]["frame"] = 0.5; },
            "camera_path[0].frame: expected an integer, got number"},
           {[](json& j) { j["camera_path"][1]["up"] = {0, 1, 0}; }, "camera_path[1].up: unknown key"},
           {[](json& j) { j["camera_path"][1].erase("look_at"); }, "camera_path[1].look_at: missing required key"},
           {[](json& j) { j["camera_path"][0].erase("frame"); }, "camera_path[0].frame: missing required key"},
           {[](json& j) { j["camera_path"][1]["position"] = {1, 2, 3, 4}; },
            "camera_path[1].position: expected an array of 3 numbers"},
           {[](json& j) { j["camera_path"][1]["look_at"] = {30, 5, -20}; }, "camera_path[1].look_at: same as position"},
           {[](json& j) {
              j["camera_path"][1]["position"] = {-1.7e308, 5, -20};
              j["camera_path"][1]["look_at"] = {1.7e308, 0, 10};
            },
            "camera_path[1].look_at: too far from position (their difference overflows a double)"},
           {[](json& j) {
              j["camera_path"][0] = {{"frame", 0}, {"position", {-1e308, 10, -60}}, {"look_at", {-1e308, 0, 0}}};
              j["camera_path"][1] = {{"frame", 100}, {"position", {1e308, 5, -20}}, {"look_at", {1e308, 0, 10}}};
            },
            "camera_path[1].position: too far from camera_path[0]'s (their difference overflows a double)"},
           {[](json& j) {
              j["camera_path"][0] = {{"frame", 0}, {"position", {0, 10, -60}}, {"look_at", {-1e308, 0, 0}}};
              j["camera_path"][1] = {{"frame", 100}, {"position", {0, 5, -20}}, {"look_at", {1e308, 0, 10}}};
            },
            "camera_path[1].look_at: too far from camera_path[0]'s (their difference overflows a double)"},
           {[](json& j) { j["camera_path"][1]["look_at"] = {30, 50, -20}; },
            "camera_path[1].look_at: view direction parallel to camera.up"},
           // Keys 0 and 1 look +z and -z: half way the view direction is zero.
           {[](json& j) {
              j["camera_path"][0] = {{"frame", 0}, {"position", {0, 0, 0}}, {"look_at", {0, 0, 1}}};
              j["camera_path"][1] = {{"frame", 100}, {"position", {0, 0, 2}}, {"look_at", {0, 0, 1}}};
            },
            "camera_path[1]: the camera looks along camera.up or at its own position at frame 50, between keys 0 "
            "and 1"},
           // Keys looking +x and -x from points 0.5 apart in y: at frame 50 it looks straight up.
           {[](json& j) {
              j["camera_path"][0] = {{"frame", 0}, {"position", {0, 0, 0}}, {"look_at", {1, 0, 0}}};
              j["camera_path"][1] = {{"frame", 100}, {"position", {0, 1, 0}}, {"look_at", {-1, 2, 0}}};
            },
            "camera_path[1]: the camera looks along camera.up or at its own position at frame 50, between keys 0 "
            "and 1"},
       }) {
    json j = moving_camera_scene();
    c.edit(j);
    EXPECT_EQ(error_of(j), c.message);
  }
  // Non-finite numbers inside the new keys, as in the old ones.
  for (const char* where : {"angular_velocity", "camera_path"}) {
    json j = moving_camera_scene();
    if (std::string(where) == "camera_path") j["camera_path"][1]["look_at"][2] = 12345.25;
    else j["objects"][1]["angular_velocity"][0] = 12345.25;
    std::string text = j.dump();
    text.replace(text.find("12345.25"), 8, "1e999");
    EXPECT_EQ(error_of(text), std::string(where) == "camera_path" ? "camera_path[1].look_at[2]: not a finite number"
                                                                   : "objects[1].angular_velocity[0]: not a finite number");
  }
  // An interpolated view direction that only comes near up (not onto it) is fine.
  json j = moving_camera_scene();
  j["camera_path"][0] = {{"frame", 0}, {"position", {0, 0, 0}}, {"look_at", {1, 0, 0}}};
  j["camera_path"][1] = {{"frame", 100}, {"position", {0, 1, 0}}, {"look_at", {-1, 2, 0.1}}};
  EXPECT_EQ(error_of(j), "");
}

TEST(SceneMotion, WrittenOnlyWhenPresentAndReadBackExactly) {
  Result<Scene> plain = parse_scene(good_scene().dump(), "");
  ASSERT_TRUE(plain);
  const std::string text = write_scene(*plain, "b");
  EXPECT_EQ(text.find("angular_velocity"), std::string::npos);
  EXPECT_EQ(text.find("camera_path"), std::string::npos);

  std::mt19937 rng(77);
  auto real = [&](double lo, double hi) { return lo + (hi - lo) * (rng() * 0x1p-32); };
  for (int round = 0; round < 30; ++round) {
    Scene s = *plain;
    for (SceneObject& o : s.objects)
      if (rng() % 2) o.angular_velocity = {real(-10, 10), real(-1e-7, 1e-7), real(-3, 3)};
    int64_t frame = rng() % 5;
    for (int k = 0, n = static_cast<int>(rng() % 5); k < n; ++k) {
      CameraKey key;
      key.frame = frame;
      frame += 1 + rng() % 1000;
      key.position = {real(-50, 50), real(-50, 50), real(-50, -40)};
      key.look_at = {real(-1, 1), real(-1, 1), real(0, 1)};
      s.camera_path.push_back(key);
    }
    Result<Scene> back = parse_scene(write_scene(s, "b"), "");
    ASSERT_TRUE(back) << back.error().message;
    ASSERT_EQ(back->objects.size(), s.objects.size());
    for (size_t i = 0; i < s.objects.size(); ++i)
      EXPECT_EQ(back->objects[i].angular_velocity, s.objects[i].angular_velocity);
    ASSERT_EQ(back->camera_path.size(), s.camera_path.size());
    for (size_t k = 0; k < s.camera_path.size(); ++k) {
      EXPECT_EQ(back->camera_path[k].frame, s.camera_path[k].frame);
      EXPECT_EQ(back->camera_path[k].position, s.camera_path[k].position);
      EXPECT_EQ(back->camera_path[k].look_at, s.camera_path[k].look_at);
    }
    EXPECT_EQ(write_scene(*back, "b"), write_scene(s, "b"));
  }
}

}  // namespace
}  // namespace octbake::scene
