#include "scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <set>
#include <nlohmann/json.hpp>

#include "text_file.h"

namespace octbake::scene {
namespace {

using nlohmann::json;

constexpr const char* kFormat = "octbake-scene/1";
// Read whole before parsing: ~200 bytes an object, so ~5 million objects.
constexpr size_t kMaxSceneBytes = size_t{1} << 30;
constexpr double kUnitTolerance = 1e-6;
constexpr int kMaxWorldDepth = 10;

// Validation stops at the first problem; the exception never leaves this file.
struct Invalid {
  std::string message;
};

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
  throw Invalid{(path.empty() ? std::string("(root)") : path) + ": " + reason};
}

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string index(const std::string& path, size_t i) { return path + "[" + std::to_string(i) + "]"; }

const char* type_name(const json& j) {
  if (j.is_number()) return "number";
  return j.type_name();
}

void check_keys(const json& obj, const std::string& path, std::initializer_list<const char*> allowed) {
  if (!obj.is_object()) fail(path, std::string("expected an object, got ") + type_name(obj));
  for (const auto& [key, value] : obj.items()) {
    bool known = false;
    for (const char* a : allowed) known = known || key == a;
    if (!known) fail(join(path, key), "unknown key");
  }
}

const json* find(const json& obj, const char* key) {
  auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

const json& require(const json& obj, const std::string& path, const char* key) {
  const json* v = find(obj, key);
  if (!v) fail(join(path, key), "missing required key");
  return *v;
}

double number(const json& j, const std::string& path) {
  if (!j.is_number()) fail(path, std::string("expected a number, got ") + type_name(j));
  double v = j.get<double>();
  if (!std::isfinite(v)) fail(path, "not a finite number");
  return v;
}

int64_t integer(const json& j, const std::string& path) {
  if (!j.is_number_integer()) fail(path, std::string("expected an integer, got ") + type_name(j));
  if (j.is_number_unsigned() && j.get<uint64_t>() > static_cast<uint64_t>(INT64_MAX))
    fail(path, "integer out of range");
  return j.get<int64_t>();
}

std::string string(const json& j, const std::string& path) {
  if (!j.is_string()) fail(path, std::string("expected a string, got ") + type_name(j));
  std::string s = j.get<std::string>();
  if (s.empty()) fail(path, "must not be empty");
  return s;
}

template <size_t N>
std::array<double, N> numbers(const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != N)
    fail(path, "expected an array of " + std::to_string(N) + " numbers");
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i) out[i] = number(j[i], index(path, i));
  return out;
}

Eigen::Vector3d vec3(const json& j, const std::string& path) {
  auto a = numbers<3>(j, path);
  return {a[0], a[1], a[2]};
}

// The reason for a point whose difference from `other` overflows.
std::string too_far_from(const std::string& other) {
  return "too far from " + other + " (their difference overflows a double)";
}

// A camera that can look: a view direction, not parallel to `up` (non-zero).
bool has_view(const Camera& c) {
  if (c.look_at == c.position) return false;
  // Stable: a camera 1e200 from its target (|d|^2 overflows) still looks.
  const Eigen::Vector3d forward = (c.look_at - c.position).stableNormalized();
  return forward.cross(c.up.stableNormalized()).norm() >= 1e-9;
}

Camera parse_camera(const json& j, const std::string& path) {
  check_keys(j, path, {"position", "look_at", "up", "fov_y_deg", "viewport", "near", "far"});
  Camera c;
  c.position = vec3(require(j, path, "position"), join(path, "position"));
  c.look_at = vec3(require(j, path, "look_at"), join(path, "look_at"));
  if (c.look_at == c.position) fail(join(path, "look_at"), "same as position");
  if (!(c.look_at - c.position).allFinite()) fail(join(path, "look_at"), too_far_from("position"));
  if (const json* v = find(j, "up")) c.up = vec3(*v, join(path, "up"));
  if (c.up.isZero(0) || !has_view(c)) fail(join(path, "up"), "zero or parallel to the view direction");
  if (const json* v = find(j, "fov_y_deg")) {
    c.fov_y_deg = number(*v, join(path, "fov_y_deg"));
    if (!(c.fov_y_deg > 0 && c.fov_y_deg < 180)) fail(join(path, "fov_y_deg"), "must be in (0, 180)");
  }
  if (const json* v = find(j, "viewport")) {
    std::string p = join(path, "viewport");
    if (!v->is_array() || v->size() != 2) fail(p, "expected an array of 2 integers");
    int64_t size[2];
    for (size_t i = 0; i < 2; ++i) {
      size[i] = integer((*v)[i], index(p, i));
      if (size[i] <= 0 || size[i] > (1 << 20)) fail(index(p, i), "must be in 1..1048576");
    }
    c.viewport_w = static_cast<int>(size[0]);
    c.viewport_h = static_cast<int>(size[1]);
  }
  if (const json* v = find(j, "near")) {
    c.near_plane = number(*v, join(path, "near"));
    if (!(c.near_plane > 0)) fail(join(path, "near"), "must be > 0");
  }
  if (const json* v = find(j, "far")) c.far_plane = number(*v, join(path, "far"));
  if (!(c.far_plane > c.near_plane)) fail(join(path, "far"), "must be > near");
  return c;
}

// The keys, and a camera that can look at every frame the path gives (between
// keys too: an interpolated view direction can pass through zero or `up`).
std::vector<CameraKey> parse_camera_path(const json& j, const Camera& base) {
  if (!j.is_array()) fail("camera_path", std::string("expected an array, got ") + type_name(j));
  std::vector<CameraKey> keys;
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string path = index("camera_path", i);
    check_keys(j[i], path, {"frame", "position", "look_at"});
    CameraKey k;
    k.frame = integer(require(j[i], path, "frame"), join(path, "frame"));
    if (k.frame < 0) fail(join(path, "frame"), "must be >= 0");
    if (!keys.empty() && k.frame <= keys.back().frame) fail(join(path, "frame"), "frames must be strictly ascending");
    k.position = vec3(require(j[i], path, "position"), join(path, "position"));
    k.look_at = vec3(require(j[i], path, "look_at"), join(path, "look_at"));
    if (k.look_at == k.position) fail(join(path, "look_at"), "same as position");
    if (!(k.look_at - k.position).allFinite()) fail(join(path, "look_at"), too_far_from("position"));
    // camera_on_path interpolates from key to key.
    if (!keys.empty()) {
      const std::string previous = index("camera_path", i - 1) + "'s";
      if (!(k.position - keys.back().position).allFinite()) fail(join(path, "position"), too_far_from(previous));
      if (!(k.look_at - keys.back().look_at).allFinite()) fail(join(path, "look_at"), too_far_from(previous));
    }
    keys.push_back(k);
    if (!has_view(camera_on_path(base, keys, k.frame)))
      fail(join(path, "look_at"), "view direction parallel to camera.up");
  }
  for (size_t i = 1; i < keys.size(); ++i) {
    // d(t) x up is linear in t: check the frames around its smallest norm.
    const CameraKey &k0 = keys[i - 1], &k1 = keys[i];
    Eigen::Vector3d d0 = k0.look_at - k0.position, d1 = k1.look_at - k1.position;
    // Scaled by a power of two (exact, so t keeps its bits) to largest
    // coordinate ~1: the squares below neither over- nor underflow.
    const int e = std::ilogb(std::max(d0.cwiseAbs().maxCoeff(), d1.cwiseAbs().maxCoeff()));
    const auto scale = [e](double x) { return std::ldexp(x, -e); };
    d0 = d0.unaryExpr(scale), d1 = d1.unaryExpr(scale);
    const Eigen::Vector3d up = base.up.normalized();
    const Eigen::Vector3d a = d0.cross(up), b = (d1 - d0).cross(up);
    const double t = b.squaredNorm() > 0 ? std::clamp(-a.dot(b) / b.squaredNorm(), 0.0, 1.0) : 0.0;
    const double span = static_cast<double>(k1.frame - k0.frame);
    const double offset = std::floor(t * span);  // < span unless t == 1: the cast cannot overflow
    const int64_t below = offset >= span ? k1.frame : k0.frame + static_cast<int64_t>(offset);
    for (int64_t f : {below, std::min(below + 1, k1.frame)}) {
      if (!has_view(camera_on_path(base, keys, f)))
        fail(index("camera_path", i), "the camera looks along camera.up or at its own position at frame " +
                                          std::to_string(f) + ", between keys " + std::to_string(i - 1) + " and " +
                                          std::to_string(i));
    }
  }
  return keys;
}

SceneObject parse_object(const json& j, const std::string& path) {
  check_keys(j, path, {"name", "model", "position", "rotation", "scale", "velocity", "angular_velocity"});
  SceneObject o;
  o.name = string(require(j, path, "name"), join(path, "name"));
  // Names go unquoted into the CSV log: no separator, quote, line break,
  // nor a NUL or other control character that a reader could cut at.
  if (std::any_of(o.name.begin(), o.name.end(),
                  [](char c) { return c == ',' || c == '"' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }))
    fail(join(path, "name"), "must not contain a comma, a quote, a line break or another control character");
  o.model = string(require(j, path, "model"), join(path, "model"));
  o.pose.position = vec3(require(j, path, "position"), join(path, "position"));
  if (const json* v = find(j, "rotation")) {
    auto q = numbers<4>(*v, join(path, "rotation"));
    Eigen::Quaterniond r(q[3], q[0], q[1], q[2]);  // [x, y, z, w] in the file
    if (!(std::abs(r.norm() - 1) <= kUnitTolerance)) fail(join(path, "rotation"), "not a unit quaternion");
    o.pose.rotation = r.normalized();
  }
  if (const json* v = find(j, "scale")) {
    o.pose.scale = number(*v, join(path, "scale"));
    if (!(o.pose.scale > 0)) fail(join(path, "scale"), "must be > 0");
  }
  if (const json* v = find(j, "velocity")) o.velocity = vec3(*v, join(path, "velocity"));
  if (const json* v = find(j, "angular_velocity")) {
    o.angular_velocity = vec3(*v, join(path, "angular_velocity"));
    if (!std::isfinite(o.angular_velocity.norm())) fail(join(path, "angular_velocity"), "rate too large");
  }
  return o;
}

// The scene's "objects", converted as the reader meets them (a document of
// them all took ~2 KB an object).
struct StreamedObjects {
  std::vector<SceneObject> objects;
  std::set<std::string> names;
  std::optional<Invalid> first_error;  // reported after the other keys' errors, as before
};

Scene parse(const json& root, const std::string& scene_dir, StreamedObjects& streamed) {
  check_keys(root, "", {"format", "baked", "camera", "camera_path", "world", "timestep", "frames", "objects"});
  Scene s;
  std::string format = string(require(root, "", "format"), "format");
  if (format != kFormat) fail("format", "expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");

  std::string baked = "baked";
  if (const json* v = find(root, "baked")) baked = string(*v, "baked");
  std::filesystem::path b(baked);
  s.baked = (b.is_absolute() || scene_dir.empty()) ? baked : (std::filesystem::path(scene_dir) / b).string();

  s.camera = parse_camera(require(root, "", "camera"), "camera");
  if (const json* v = find(root, "camera_path")) s.camera_path = parse_camera_path(*v, s.camera);

  const json& world = require(root, "", "world");
  check_keys(world, "world", {"min", "max", "depth"});
  s.world.min = vec3(require(world, "world", "min"), "world.min");
  s.world.max = vec3(require(world, "world", "max"), "world.max");
  for (int a = 0; a < 3; ++a)
    if (!(s.world.min[a] < s.world.max[a])) fail("world.max", "must be > world.min on every axis");
  if (const json* v = find(world, "depth")) {
    int64_t d = integer(*v, "world.depth");
    if (d < 0 || d > kMaxWorldDepth) fail("world.depth", "must be in 0..10");
    s.world_depth = static_cast<int>(d);
  }

  s.timestep = number(require(root, "", "timestep"), "timestep");
  if (!(s.timestep > 0)) fail("timestep", "must be > 0");
  s.frames = integer(require(root, "", "frames"), "frames");
  if (s.frames < 0 || s.frames > kMaxFrames) fail("frames", "must be in 0..100000000");

  const json& objects = require(root, "", "objects");
  if (!objects.is_array()) fail("objects", std::string("expected an array, got ") + type_name(objects));
  if (streamed.first_error) throw *streamed.first_error;
  s.objects = std::move(streamed.objects);
  return s;
}

// One element of "objects", as its last event arrives.
void take_object(const json& element, size_t i, StreamedObjects& streamed) {
  if (streamed.first_error) return;  // validation stops at the first problem
  try {
    const std::string path = index("objects", i);
    streamed.objects.push_back(parse_object(element, path));
    if (!streamed.names.insert(streamed.objects.back().name).second)
      fail(join(path, "name"), "duplicate name \"" + streamed.objects.back().name + "\"");
  } catch (const Invalid& e) {
    streamed.first_error = e;
  }
}

// One pass over the text (SAX events) that follows the JSON path, so that the
// two errors nlohmann would not place can say where they are: a duplicate key
// (nlohmann keeps the last; a scene must not say two things) and a number
// beyond double (1e999). It builds the document, except that each element of
// the top-level "objects" array is built alone, handed to take_object and
// dropped: a 100,000-object scene's document took ~200 MB. (nlohmann's
// callback parser could drop them too, but it scans the whole parent array
// after every object: 100,000 objects took 2.7 s.)
class SceneReader : public nlohmann::json_sax<json> {
 public:
  explicit SceneReader(StreamedObjects& streamed) : streamed_(streamed) {}

  bool null() override { return value(json()); }
  bool boolean(bool v) override { return value(json(v)); }
  bool number_integer(number_integer_t v) override { return value(json(v)); }
  bool number_unsigned(number_unsigned_t v) override { return value(json(v)); }
  bool number_float(number_float_t v, const string_t&) override { return value(json(v)); }
  bool string(string_t& v) override { return value(json(v)); }
  bool binary(binary_t& v) override { return value(json::binary(std::move(v))); }
  bool start_object(std::size_t) override { return open(false); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& key) override {
    Frame& top = stack_.back();
    top.key = key;
    if (!top.keys.insert(key).second) {
      error = path() + ": duplicate key";
      return false;
    }
    return true;
  }
  bool parse_error(std::size_t byte, const std::string&, const json::exception& e) override {
    if (e.id == 406) {  // out_of_range: a number beyond double
      error = path() + ": not a finite number";
    } else {
      // e.what() reads "[json.exception.parse_error.101] parse error at line L, column C: REASON".
      const std::string what = e.what();
      const size_t colon = what.find(": ");
      syntax_error_byte = byte;
      syntax_error = colon == std::string::npos ? what : what.substr(colon + 2);
    }
    return false;
  }

  json root;
  std::string error;         // a duplicate key or a number beyond double, with its path
  std::string syntax_error;  // not JSON: the reason, at syntax_error_byte
  size_t syntax_error_byte = 0;

 private:
  struct Frame {
    bool is_array;
    size_t count;  // elements so far (arrays)
    std::string key;
    std::set<std::string> keys;
    json* value;  // the object or array being built
  };

  // Is the next value an element of the top-level "objects" array?
  bool at_object_element() const {
    return stack_.size() == 2 && !stack_[0].is_array && stack_[0].key == "objects" && stack_[1].is_array;
  }
  // Where a value that starts now goes: in its parent, or alone (an element
  // of "objects").
  json* place(json&& v) {
    if (stack_.empty()) return &(root = std::move(v));
    if (at_object_element()) return &(element_ = std::move(v));
    Frame& top = stack_.back();
    if (top.is_array) {
      top.value->push_back(std::move(v));
      return &top.value->back();
    }
    return &((*top.value)[top.key] = std::move(v));
  }
  // A value is complete: count it, and hand an element of "objects" over.
  void done() {
    if (stack_.empty()) return;
    if (at_object_element()) take_object(element_, stack_.back().count, streamed_);
    if (stack_.back().is_array) ++stack_.back().count;
  }
  bool value(json&& v) {
    place(std::move(v));
    done();
    return true;
  }
  bool open(bool is_array) {
    json* v = place(is_array ? json::array() : json::object());
    stack_.push_back({is_array, 0, {}, {}, v});
    return true;
  }
  bool close() {
    stack_.pop_back();
    done();
    return true;
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : stack_) p = f.is_array ? index(p, f.count) : join(p, f.key);
    return p;
  }

  StreamedObjects& streamed_;
  json element_;  // the element of "objects" being read
  std::vector<Frame> stack_;
};

std::string line_column(const std::string& text, size_t byte) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

Result<Scene> parse_scene(const std::string& json_text, const std::string& scene_dir) {
  StreamedObjects streamed;
  SceneReader reader(streamed);
  if (!json::sax_parse(json_text, &reader)) {
    if (!reader.error.empty()) return Error{ErrorCode::invalid_argument, reader.error};
    return Error{ErrorCode::invalid_argument,
                 "invalid JSON at " + line_column(json_text, reader.syntax_error_byte) + ": " + reader.syntax_error};
  }
  try {
    return parse(reader.root, scene_dir, streamed);
  } catch (const Invalid& e) {
    return Error{ErrorCode::invalid_argument, e.message};
  } catch (const json::exception& e) {
    return Error{ErrorCode::invalid_argument, e.what()};  // not expected: every access is checked
  }
}

Result<Scene> load_scene(const std::string& path) {
  Result<std::string> text = read_text_file(path, kMaxSceneBytes);
  if (!text) return text.error();
  Result<Scene> s = parse_scene(*text, std::filesystem::path(path).parent_path().string());
  if (!s) return Error{s.error().code, path + ": " + s.error().message};
  return s;
}

std::string write_scene(const Scene& scene, const std::string& baked) {
  using json = nlohmann::ordered_json;  // keys in the order written
  auto v3 = [](const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); };
  json camera = {
      {"position", v3(scene.camera.position)},  {"look_at", v3(scene.camera.look_at)},
      {"up", v3(scene.camera.up)},              {"fov_y_deg", scene.camera.fov_y_deg},
      {"viewport", {scene.camera.viewport_w, scene.camera.viewport_h}},
      {"near", scene.camera.near_plane},        {"far", scene.camera.far_plane}};
  json world = {{"min", v3(scene.world.min)}, {"max", v3(scene.world.max)}, {"depth", scene.world_depth}};
  // nlohmann prints doubles in the shortest form that reads back exactly, in
  // the "C" locale.
  std::string out = "{\n";
  out += "  \"format\": " + json(kFormat).dump() + ",\n";
  out += "  \"baked\": " + json(baked).dump() + ",\n";
  out += "  \"camera\": " + camera.dump() + ",\n";
  if (!scene.camera_path.empty()) {
    out += "  \"camera_path\": [";
    for (size_t i = 0; i < scene.camera_path.size(); ++i) {
      const CameraKey& k = scene.camera_path[i];
      json key = {{"frame", k.frame}, {"position", v3(k.position)}, {"look_at", v3(k.look_at)}};
      out += (i ? ",\n    " : "\n    ") + key.dump();
    }
    out += "\n  ],\n";
  }
  out += "  \"world\": " + world.dump() + ",\n";
  out += "  \"timestep\": " + json(scene.timestep).dump() + ",\n";
  out += "  \"frames\": " + json(scene.frames).dump() + ",\n";
  out += "  \"objects\": [";
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    const Eigen::Quaterniond& q = o.pose.rotation;
    json j = {{"name", o.name},
              {"model", o.model},
              {"position", v3(o.pose.position)},
              {"rotation", {q.x(), q.y(), q.z(), q.w()}},
              {"scale", o.pose.scale},
              {"velocity", v3(o.velocity)}};
    if (!o.angular_velocity.isZero(0)) j["angular_velocity"] = v3(o.angular_velocity);
    out += (i ? ",\n    " : "\n    ") + j.dump();
  }
  out += scene.objects.empty() ? "]\n}\n" : "\n  ]\n}\n";
  return out;
}

}  // namespace octbake::scene
