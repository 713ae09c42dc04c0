#include "bake.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <system_error>
#include <thread>
#include <utility>

#include "build_tree.h"
#include "cli.h"
#include "import_child.h"
#include "octbake/baked_file.h"
#include "octbake/baker.h"
#include "write.h"

namespace octbake {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

enum class Outcome : uint8_t { pending, baked, up_to_date, failed };

struct Input {
  std::string path;    // as given on the command line
  std::string name;    // tree name: the file's stem
  std::string output;  // per-file mode: DIR/<name>.oct
  std::string hash;
  std::optional<TreeToEncode> tree;  // pack mode: baked, waiting to be packed
};

// Collects outcomes from the workers. Error lines go out in input order: the
// line of input i waits until every earlier input has finished.
class Reporter {
 public:
  Reporter(size_t n, std::FILE* err, bool progress, bool summary)
      : outcome_(n, Outcome::pending), error_(n), err_(err), progress_(progress), summary_(summary),
        start_(Clock::now()) {
    draw_line();
  }

  // Whether advance() shows anything (the progress line is on).
  bool live() const { return progress_; }

  // Input i, a mesh of `triangles`, is `fraction` (0..1) built.
  void advance(size_t i, uint64_t triangles, double fraction) {
    if (!progress_) return;
    std::lock_guard lock(mu_);
    in_flight_[i] = {double(triangles), fraction};
    // Redraw at most 10 times a second: the line is for a person.
    const Clock::time_point now = Clock::now();
    if (now - last_draw_ < std::chrono::milliseconds(100)) return;
    clear_line();
    draw_line();
  }

  void finish(size_t i, Outcome outcome, std::string error = {}, uint64_t triangles = 0) {
    std::lock_guard lock(mu_);
    outcome_[i] = outcome;
    error_[i] = std::move(error);
    triangles_ += triangles;
    in_flight_.erase(i);
    ++done_;
    clear_line();
    for (; emitted_ < outcome_.size() && outcome_[emitted_] != Outcome::pending; ++emitted_)
      if (outcome_[emitted_] == Outcome::failed) print_error(error_[emitted_]);
    draw_line();
  }

  // A failure that belongs to no single input (the pack file).
  void extra_error(const std::string& line) {
    std::lock_guard lock(mu_);
    clear_line();
    ++extra_failures_;
    print_error(line);
    draw_line();
  }

  bool finished(size_t i) {
    std::lock_guard lock(mu_);
    return outcome_[i] != Outcome::pending;
  }

  BakeSummary summary() {
    std::lock_guard lock(mu_);
    BakeSummary s;
    for (Outcome o : outcome_) {
      s.baked += o == Outcome::baked;
      s.up_to_date += o == Outcome::up_to_date;
      s.failed += o == Outcome::failed;
    }
    s.failed += extra_failures_;
    s.triangles = triangles_;
    s.errors = lines_;
    clear_line();
    if (summary_)
      std::fprintf(err_, "%s\n", summary_line(s.baked, s.up_to_date, s.failed, seconds(), triangles_).c_str());
    std::fflush(err_);
    return s;
  }

 private:
  struct Partial {
    double triangles, fraction;
  };

  double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  void print_error(const std::string& line) {
    lines_.push_back(line);
    std::fprintf(err_, "%s\n", line.c_str());
    std::fflush(err_);
  }
  void clear_line() {
    if (progress_) std::fputs("\r\033[K", err_);
  }
  void draw_line() {
    if (!progress_) return;
    ProgressCounts c;
    c.files_done = done_;
    c.files_total = outcome_.size();
    c.files_waiting = outcome_.size() - done_ - in_flight_.size();
    c.triangles_done = c.triangles_known = double(triangles_);
    for (const auto& [i, p] : in_flight_) {
      c.triangles_done += p.triangles * p.fraction;
      c.triangles_known += p.triangles;
      c.files_writing += p.fraction >= 1;
    }
    c.seconds = seconds();
    std::fputs(progress_line(c).c_str(), err_);
    std::fflush(err_);
    last_draw_ = Clock::now();
  }

  std::mutex mu_;
  std::vector<Outcome> outcome_;
  std::vector<std::string> error_;
  std::vector<std::string> lines_;
  std::map<size_t, Partial> in_flight_;  // inputs being built, by index
  std::FILE* err_;
  bool progress_, summary_;
  Clock::time_point start_, last_draw_;
  size_t done_ = 0, emitted_ = 0;
  int extra_failures_ = 0;
  uint64_t triangles_ = 0;
};

// One line whatever the path holds: a newline or carriage return in a file
// name (or in a reason quoting one) is written as \n or \r.
std::string error_line(const std::string& path, const std::string& reason) {
  std::string line = "octbake: error: ";
  for (char ch : path + ": " + reason) line += ch == '\n' ? "\\n" : ch == '\r' ? "\\r" : std::string(1, ch);
  return line;
}

// Runs fn(i) for every i in [0, n) on the calling thread and as many more as
// `budget` has slots, each holding one slot while it works. A thread that
// finds no item left gives its slot back at once, for a build still running
// (build_tree takes idle slots). Which thread runs which item never shows in
// the output: results are keyed by index.
template <class Fn>
void parallel_for(size_t n, ThreadBudget& budget, const Fn& fn) {
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i; (i = next.fetch_add(1)) < n;) fn(i);
  };
  const bool held = budget.try_acquire();  // the calling thread's own slot
  std::vector<std::jthread> pool;
  for (size_t t = 1; t < n && budget.try_acquire(); ++t) {
    try {
      pool.emplace_back([&] {
        worker();
        budget.release();
      });
    } catch (const std::system_error&) {  // no thread to be had (a pid limit): go on with those running
      budget.release();
      break;
    }
  }
  worker();
  if (held) budget.release();
}

// encode_file on the calling thread plus free slots of `budget`, as many as
// the trees' largest level can use, given back at the end. `held`: the
// calling thread holds a slot already (a parallel_for worker); else it takes
// one when free, as parallel_for does. The bytes never depend on the count.
std::vector<uint8_t> encode_with(std::span<const TreeToEncode> trees, ThreadBudget& budget, bool held) {
  struct Slots {
    ThreadBudget& budget;
    int taken = 0;
    ~Slots() {
      for (; taken > 0; --taken) budget.release();
    }
  } slots{budget};
  if (!held && budget.try_acquire()) ++slots.taken;
  int threads = 1;
  for (const int useful = encode_threads_useful(trees); threads < useful && budget.try_acquire(); ++threads)
    ++slots.taken;
  return encode_file(trees, baker_version(), threads);
}

// The masks of every tree of `path` when it holds exactly `expect` (names and
// source hashes, in order) baked with `options` by this baker and format, and
// all of its levels decode; nullopt otherwise (missing, stale or corrupt).
std::optional<std::vector<OctreeMasks>> load_if_current(const std::string& path,
                                                        const std::vector<const Input*>& expect,
                                                        const BakeOptions& options) {
  auto file = BakedFile::open(path);
  if (!file || file->format_version() != kFormatVersion || file->baker_version() != baker_version() ||
      file->trees().size() != expect.size())
    return std::nullopt;
  std::vector<OctreeMasks> masks;
  for (size_t i = 0; i < expect.size(); ++i) {
    const TreeInfo& t = file->trees()[i];
    if (t.name != expect[i]->name || t.source_hash != expect[i]->hash || !(t.options == options) ||
        t.depth != options.depth)
      return std::nullopt;
    auto tree = file->load(i, options.depth);
    if (!tree) return std::nullopt;
    masks.push_back(tree->masks());
  }
  return masks;
}

// Imports input i (public API: load_mesh, recording the files read; in a
// child process when config.import_helper is set) and builds its tree on
// threads from `threads`, showing its progress on `reporter`; the error is
// the reason only.
Result<TreeToEncode> bake_tree(const Input& in, size_t i, const BakeConfig& config, ThreadBudget& threads,
                               Reporter& reporter, std::vector<std::string>* files_read) {
  auto mesh = config.import_helper.empty()
                  ? load_mesh(in.path, files_read)
                  : load_mesh_in_child(config.import_helper, in.path, files_read, config.import_timeout_s);
  if (!mesh) return Error{mesh.error().code, error_reason(mesh.error(), in.path)};
  BuildControl control{&threads, {}};
  if (reporter.live())
    control.progress = [&reporter, i, triangles = mesh->triangles.size()](uint64_t done, uint64_t total) {
      reporter.advance(i, triangles, total > 0 ? double(done) / double(total) : 1.0);
    };
  TreeToEncode t;
  t.name = in.name;
  t.source_hash = in.hash;
  t.options = config.options;
  t.triangle_count = mesh->triangles.size();
  t.vertex_count = mesh->positions.size();
  t.masks = build_tree(*mesh, config.options.depth, config.options.occupancy, control);
  return t;
}

// A Make-syntax rule "OUTPUT: INPUT...": spaces and '#' escaped with a
// backslash, '$' doubled; both Make and Ninja read it. Make cannot name a
// file with a newline, and reads a backslash before an escaped space as
// an escape of its own: depfile_problem() refuses such paths first.
std::string depfile_text(const std::string& output, const std::vector<std::string>& inputs) {
  auto escape = [](const std::string& path) {
    std::string e;
    for (char ch : path) {
      if (ch == ' ' || ch == '#') e += '\\';
      if (ch == '$') e += '$';
      e += ch;
    }
    return e;
  };
  std::string text = escape(output) + ":";
  for (const std::string& in : inputs) text += " \\\n " + escape(in);
  return text + "\n";
}

// Why no depfile can name these paths, if it cannot.
std::optional<std::string> depfile_problem(const std::string& output, const std::vector<std::string>& inputs) {
  auto bad = [](const std::string& path) { return path.find_first_of("\n\r\\") != std::string::npos; };
  if (bad(output)) return "cannot name " + output + " in a depfile: it holds a newline or a backslash";
  for (const std::string& in : inputs)
    if (bad(in)) return "cannot name " + in + " in a depfile: it holds a newline or a backslash";
  return std::nullopt;
}

std::optional<std::string> make_dir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return "cannot create folder " + dir + ": " + ec.message();
  remove_stale_temps(dir);
  return std::nullopt;
}

class Baker {
 public:
  Baker(const BakeConfig& config, std::FILE* err) : config_(config), err_(err), threads_(std::max(config.jobs, 1)) {}

  BakeSummary run() {
    collect_inputs();
    Reporter reporter(inputs_.size(), err_, config_.progress, config_.summary);
    reporter_ = &reporter;
    find_collisions();
    prepare_dirs();
    if (config_.pack.empty())
      parallel_for(inputs_.size(), threads_, [&](size_t i) { guarded(i, [&] { bake_one(i); }); });
    else
      bake_pack();
    return reporter.summary();
  }

 private:
  // The same file named twice is baked once, at its first position.
  void collect_inputs() {
    std::vector<std::string> seen;
    for (const std::string& path : config_.inputs) {
      std::error_code ec;
      fs::path key = fs::weakly_canonical(path, ec);
      const std::string k = ec ? path : key.string();
      if (std::find(seen.begin(), seen.end(), k) != seen.end()) continue;
      seen.push_back(k);
      Input in;
      in.path = path;
      in.name = fs::path(path).stem().string();
      in.output = (fs::path(config_.out_dir) / (in.name + ".oct")).string();
      inputs_.push_back(std::move(in));
    }
  }

  // Two inputs that would write the same output (or tree name) both fail.
  void find_collisions() {
    const bool pack = !config_.pack.empty();
    std::map<std::string, std::vector<size_t>> by_key;
    for (size_t i = 0; i < inputs_.size(); ++i) {
      if (inputs_[i].name.empty()) {
        fail(i, "no file name to name the output after");
        continue;
      }
      by_key[pack ? inputs_[i].name : inputs_[i].output].push_back(i);
    }
    for (const auto& [key, group] : by_key) {
      if (group.size() < 2) continue;
      for (size_t i : group) {
        std::string others;
        for (size_t j : group)
          if (j != i) others += (others.empty() ? "" : ", ") + inputs_[j].path;
        fail(i, pack ? "tree name \"" + key + "\" in pack " + config_.pack + " would also come from " + others
                     : "output " + key + " would also be written by " + others);
      }
    }
  }

  void prepare_dirs() {
    std::vector<std::string> dirs;
    if (config_.pack.empty())
      dirs.push_back(config_.out_dir);
    else if (fs::path(config_.pack).has_parent_path())
      dirs.push_back(fs::path(config_.pack).parent_path().string());
    if (!config_.export_obj_dir.empty()) dirs.push_back(config_.export_obj_dir);
    for (const std::string& dir : dirs)
      if (auto problem = make_dir(dir))
        for (size_t i = 0; i < inputs_.size(); ++i)
          if (!reporter_->finished(i)) fail(i, *problem);
  }

  void fail(size_t i, const std::string& reason) {
    reporter_->finish(i, Outcome::failed, error_line(inputs_[i].path, reason));
  }

  // No exception (bad_alloc from a huge depth, say) escapes a worker thread.
  template <class Fn>
  void guarded(size_t i, const Fn& fn) {
    if (reporter_->finished(i)) return;
    try {
      fn();
    } catch (const std::exception& e) {
      fail(i, std::string("internal error: ") + e.what());
    }
  }

  bool hash_input(size_t i) {
    auto hash = hash_file(inputs_[i].path);
    if (!hash) {
      fail(i, error_reason(hash.error(), inputs_[i].path));
      return false;
    }
    inputs_[i].hash = std::move(*hash);
    return true;
  }

  // Writes the OBJ export of one tree; the error is a full reason or empty.
  std::string export_tree(const OctreeMasks& masks, const std::string& name) {
    if (config_.export_obj_dir.empty()) return {};
    auto r = export_obj(masks, name, config_.export_obj_dir);
    return r ? std::string() : "cannot export OBJ to " + config_.export_obj_dir + ": " + r.error().message;
  }

  void bake_one(size_t i) {
    Input& in = inputs_[i];
    if (!hash_input(i)) return;
    if (!config_.force) {
      if (auto masks = load_if_current(in.output, {&in}, config_.options)) {
        const std::string problem = export_tree(masks->front(), in.name);
        if (!problem.empty()) return fail(i, problem);
        return reporter_->finish(i, Outcome::up_to_date);
      }
    }
    std::vector<std::string> files_read;
    auto tree = bake_tree(in, i, config_, threads_, *reporter_, &files_read);
    if (!tree) return fail(i, tree.error().message);
    const std::vector<uint8_t> bytes = encode_with({&*tree, 1}, threads_, /*held=*/true);
    auto written = write_file_atomic(in.output, bytes);
    if (!written) return fail(i, "cannot write " + in.output + ": " + written.error().message);
    if (!config_.depfile.empty()) {
      std::error_code ec;
      fs::create_directories(fs::absolute(config_.depfile, ec).parent_path(), ec);
      const std::string output = fs::absolute(in.output, ec).lexically_normal().string();
      if (auto problem = depfile_problem(ec ? in.output : output, files_read)) return fail(i, *problem);
      const std::string text = depfile_text(ec ? in.output : output, files_read);
      auto dep = write_file_atomic(config_.depfile, {reinterpret_cast<const uint8_t*>(text.data()), text.size()});
      if (!dep) return fail(i, "cannot write depfile " + config_.depfile + ": " + dep.error().message);
    }
    const std::string problem = export_tree(tree->masks, in.name);
    if (!problem.empty()) return fail(i, problem);
    reporter_->finish(i, Outcome::baked, {}, tree->triangle_count);
  }

  // Pack: hash everything, skip when the pack already holds exactly these
  // trees, else bake in parallel and encode once, in input order.
  void bake_pack() {
    std::vector<uint8_t> hashed(inputs_.size(), 0);
    parallel_for(inputs_.size(), threads_, [&](size_t i) { guarded(i, [&] { hashed[i] = hash_input(i); }); });
    std::vector<const Input*> expect;
    for (size_t i = 0; i < inputs_.size(); ++i)
      if (hashed[i]) expect.push_back(&inputs_[i]);
    if (expect.empty()) return;

    if (!config_.force) {
      if (auto masks = load_if_current(config_.pack, expect, config_.options)) {
        for (size_t k = 0, i = 0; i < inputs_.size(); ++i) {
          if (!hashed[i]) continue;
          const std::string problem = export_tree((*masks)[k++], inputs_[i].name);
          if (problem.empty())
            reporter_->finish(i, Outcome::up_to_date);
          else
            fail(i, problem);
        }
        return;
      }
    }

    parallel_for(inputs_.size(), threads_, [&](size_t i) {
      guarded(i, [&] {
        auto tree = bake_tree(inputs_[i], i, config_, threads_, *reporter_, nullptr);
        if (!tree) return fail(i, tree.error().message);
        const std::string problem = export_tree(tree->masks, inputs_[i].name);
        if (!problem.empty()) return fail(i, problem);
        const uint64_t triangles = tree->triangle_count;
        inputs_[i].tree = std::move(*tree);
        reporter_->finish(i, Outcome::baked, {}, triangles);
      });
    });

    std::vector<TreeToEncode> trees;
    for (Input& in : inputs_)
      if (in.tree) trees.push_back(std::move(*in.tree));
    if (trees.empty()) return;  // keep the old pack: nothing to put in it
    // A pack is one file: rewritten without a failed input's tree, it would
    // lose the tree the old pack holds. Nothing already made is lost.
    std::error_code ec;
    if (const size_t failed = inputs_.size() - trees.size(); failed > 0 && fs::exists(config_.pack, ec))
      return reporter_->extra_error(error_line(
          config_.pack, "not rewritten, the old pack is kept: " + std::to_string(failed) + " of " +
                            std::to_string(inputs_.size()) + " inputs failed (fix them or leave them out)"));
    std::vector<uint8_t> bytes;
    try {  // zstd out of memory or threads: one error line, the old pack kept
      bytes = encode_with(trees, threads_, /*held=*/false);
    } catch (const std::exception& e) {
      return reporter_->extra_error(error_line(config_.pack, std::string("internal error: ") + e.what()));
    }
    auto written = write_file_atomic(config_.pack, bytes);
    if (!written) reporter_->extra_error(error_line(config_.pack, "cannot write: " + written.error().message));
  }

  const BakeConfig& config_;
  std::FILE* err_;
  ThreadBudget threads_;  // -j: shared by the files and the builds within them
  std::vector<Input> inputs_;
  Reporter* reporter_ = nullptr;
};

void append_number(std::string& s, double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  s.append(buf, r.ptr);
}

}  // namespace

BakeSummary run_bake(const BakeConfig& config, std::FILE* err) { return Baker(config, err).run(); }

std::string obj_text(const OctreeMasks& masks, const std::string& name, int depth) {
  // Corner k of a box: x = bit 0, y = bit 1, z = bit 2 (the octant order).
  // Quads wind counter-clockwise seen from outside.
  static constexpr int kQuads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  const std::vector<BoxCoord> boxes = masks.boxes(depth);
  std::string s = "# octbake boxes: tree " + name + ", depth " + std::to_string(depth) + ", " +
                  std::to_string(boxes.size()) + " boxes\n";
  s.reserve(boxes.size() * 400);
  uint64_t base = 1;
  for (const BoxCoord& c : boxes) {
    const Aabb b = masks.box_bounds(depth, c);
    for (int k = 0; k < 8; ++k) {
      s += 'v';
      for (int axis = 0; axis < 3; ++axis) {
        s += ' ';
        append_number(s, (k >> axis) & 1 ? b.max[axis] : b.min[axis]);
      }
      s += '\n';
    }
    for (const auto& quad : kQuads) {
      s += 'f';
      for (int corner : quad) s += ' ' + std::to_string(base + corner);
      s += '\n';
    }
    base += 8;
  }
  return s;
}

Result<uint64_t> export_obj(const OctreeMasks& masks, const std::string& name, const std::string& dir) {
  uint64_t total = 0;
  for (int d = 0; d <= masks.depth(); ++d) {
    const std::string text = obj_text(masks, name, d);
    const std::string path = (fs::path(dir) / (name + "_d" + std::to_string(d) + ".obj")).string();
    auto written =
        write_file_atomic(path, {reinterpret_cast<const uint8_t*>(text.data()), text.size()});
    if (!written) return Error{written.error().code, path + ": " + written.error().message};
    total += *written;
  }
  return total;
}

}  // namespace octbake
