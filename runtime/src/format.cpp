// encode_file(): TreeToEncode -> the bytes of schema/octbake.fbs, always the
// newest format version (kFormatVersion). Its readers, one per version, are
// beside it in baked_file.cpp (BakedFile::Impl::verify / decode_level).
#include "octbake/format.h"

#include <zstd.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <future>
#include <memory>
#include <new>
#include <set>
#include <system_error>

#include "octbake_generated.h"

namespace octbake {
namespace {

// The public enums mirror the schema's, value for value.
static_assert(uint8_t(Compression::none) == uint8_t(fb::Compression::None));
static_assert(uint8_t(Compression::zstd) == uint8_t(fb::Compression::Zstd));
static_assert(uint8_t(Occupancy::surface) == uint8_t(fb::Occupancy::Surface));
static_assert(uint8_t(Occupancy::solid) == uint8_t(fb::Occupancy::Solid));
static_assert(uint8_t(Occupancy::vertices) == uint8_t(fb::Occupancy::Vertices));

using CCtxPtr = std::unique_ptr<ZSTD_CCtx, decltype(&ZSTD_freeCCtx)>;

// zstd's multithreaded mode (nbWorkers >= 1) writes the same frame for any
// worker count, given the same job size and overlap (zstd >= 1.4.7; tested
// by EncodeThreads in tests/unit/baker/cli_jobs_test.cpp), but not the frame
// of the single-threaded mode: every thread count, 1 included, uses it. zstd
// compresses an input of at most kMinJob single-threaded whatever nbWorkers
// says, so small levels keep the single-threaded frames.
constexpr size_t kMinJob = size_t(512) << 10;  // ZSTDMT_JOBSIZE_MIN
constexpr size_t kMaxJob = size_t(4) << 20;
constexpr size_t kMostJobs = 8;  // enough to balance a few threads
// Each job is primed with the last 1/16 of a window of the job before it (512
// KiB at level 19): most of the long matches for a few percent of size.
// Priming costs about what compressing the same bytes does, so a full-window
// overlap would double the work.
constexpr int kOverlapLog = 5;

// Jobs of a level: as many as fit whole jobs of kMinJob, at most kMostJobs
// unless that makes jobs larger than kMaxJob. Equal jobs (1.3 MB is two
// of 650 KB, not 512 + 512 + 276, whose last job runs alone on two threads).
// Depends on the level's size only, never on the threads.
size_t job_count(size_t raw) {
  const size_t fit = std::max<size_t>(raw / kMinJob, 1);
  return std::max(std::min(fit, kMostJobs), (raw + kMaxJob - 1) / kMaxJob);
}

size_t job_size(size_t raw) {
  const size_t count = job_count(raw);
  return std::max((raw + count - 1) / count, kMinJob);
}

// A libzstd built without threads: single-threaded frames for every level,
// still the same bytes for every thread count.
bool zstd_has_threads() {
  static const bool has = [] {
    const ZSTD_bounds b = ZSTD_cParam_getBounds(ZSTD_c_nbWorkers);
    return !ZSTD_isError(b.error) && b.upperBound >= 1;
  }();
  return has;
}

// One zstd frame with the same bytes on every run and for every `threads`:
// content size and checksum recorded, no dictionary id, nothing
// time-dependent.
std::vector<uint8_t> zstd_frame(ZSTD_CCtx* cctx, std::span<const uint8_t> raw, int level, int threads) {
  ZSTD_CCtx_reset(cctx, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_contentSizeFlag, 1);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_dictIDFlag, 0);
  if (zstd_has_threads()) {
    const size_t workers = std::min({size_t(threads), job_count(raw.size()), size_t(256)});
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_nbWorkers, int(workers));
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_jobSize, int(job_size(raw.size())));
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_overlapLog, kOverlapLog);
  }
  std::vector<uint8_t> frame(ZSTD_compressBound(raw.size()));
  const size_t n = ZSTD_compress2(cctx, frame.data(), frame.size(), raw.data(), raw.size());
  // The bound always fits: only memory (or a thread) can be missing, and a
  // raw level instead would make the bytes depend on it.
  if (ZSTD_isError(n)) throw std::bad_alloc();
  frame.resize(n);
  return frame;
}

// A level zstd's workers compress in several jobs at once.
bool split_in_jobs(size_t raw) { return zstd_has_threads() && job_count(raw) > 1; }

// The zstd frame of each level of `masks` (depth 1 first), or an empty vector
// where the frame would not be smaller than the raw level. Never more than
// `threads` compressions at once (three zstd:19 runs on two cores take twice
// one, not 1.5 times): first the one-job levels, largest first, on the
// calling thread and up to threads - 1 helpers; then each split level on
// zstd's `threads` workers, its jobs equal so that the threads end together.
// Every frame is a function of its level's bytes only: the same for every
// `threads`.
std::vector<std::vector<uint8_t>> compress_levels(ZSTD_CCtx* cctx, const OctreeMasks& masks, int level,
                                                  int threads) {
  const int depth = masks.depth();
  std::vector<std::vector<uint8_t>> frames(depth);
  auto compress = [&](ZSTD_CCtx* c, int d) {
    const std::vector<uint8_t>& raw = masks.masks[d];
    std::vector<uint8_t> frame = zstd_frame(c, raw, level, threads);
    if (frame.size() < raw.size()) frames[d] = std::move(frame);
  };
  std::vector<int> split, single;
  for (int d = 0; d < depth; ++d) (split_in_jobs(masks.masks[d].size()) ? split : single).push_back(d);
  std::stable_sort(single.begin(), single.end(),
                   [&](int a, int b) { return masks.masks[a].size() > masks.masks[b].size(); });
  std::atomic<size_t> next{0};
  auto take_singles = [&](ZSTD_CCtx* c) {
    for (size_t i; (i = next.fetch_add(1)) < single.size();) compress(c, single[i]);
  };
  // The futures of std::async wait for their thread when destroyed, so an
  // exception leaves only after every helper has stopped writing `frames`.
  std::vector<std::future<void>> helpers;
  for (size_t h = 0; h + 1 < std::min(size_t(threads), single.size()); ++h) {
    try {
      helpers.push_back(std::async(std::launch::async, [&] {
        CCtxPtr own(ZSTD_createCCtx(), ZSTD_freeCCtx);
        if (!own) throw std::bad_alloc();
        take_singles(own.get());
      }));
    } catch (const std::system_error&) {
      break;  // no thread to be had: go on with those running
    }
  }
  try {
    take_singles(cctx);
  } catch (...) {
    next = single.size();  // the helpers take nothing more
    throw;
  }
  for (std::future<void>& f : helpers) f.get();  // a helper's exception, if any
  for (int d : split) compress(cctx, d);
  return frames;
}

flatbuffers::Offset<fb::Tree> encode_tree(flatbuffers::FlatBufferBuilder& fbb, ZSTD_CCtx* cctx,
                                          const TreeToEncode& tree, int threads) {
  const OctreeMasks& masks = tree.masks;
  const int depth = masks.depth();
  assert(depth == tree.options.depth && depth >= 1 && depth <= kMaxDepth);
  assert(!tree.name.empty());
  assert(masks.bounds.min.allFinite() && masks.bounds.max.allFinite());
  assert((masks.bounds.min.array() <= masks.bounds.max.array()).all());

  std::vector<std::vector<uint8_t>> frames;
  if (tree.options.compression == Compression::zstd)
    frames = compress_levels(cctx, masks, tree.options.compression_level, threads);
  std::vector<flatbuffers::Offset<fb::Level>> levels;
  levels.push_back(fb::CreateLevel(fbb, /*box_count=*/1, /*raw_size=*/0, fb::Compression::None,
                                   fbb.CreateVector(std::vector<uint8_t>{})));
  for (int d = 1; d <= depth; ++d) {
    const std::vector<uint8_t>& raw = masks.masks[d - 1];
    assert(raw.size() == masks.box_count(d - 1));
    const bool zstd = !frames.empty() && !frames[d - 1].empty();
    levels.push_back(fb::CreateLevel(fbb, masks.box_count(d), raw.size(),
                                     zstd ? fb::Compression::Zstd : fb::Compression::None,
                                     fbb.CreateVector(zstd ? frames[d - 1] : raw)));
  }
  const auto levels_offset = fbb.CreateVector(levels);
  const auto name = fbb.CreateString(tree.name);
  const auto source_hash = fbb.CreateString(tree.source_hash);
  const auto options =
      fb::CreateBakeOptions(fbb, static_cast<uint8_t>(depth), static_cast<fb::Occupancy>(tree.options.occupancy),
                            static_cast<fb::Compression>(tree.options.compression), tree.options.compression_level);
  const fb::Vec3 lo(masks.bounds.min.x(), masks.bounds.min.y(), masks.bounds.min.z());
  const fb::Vec3 hi(masks.bounds.max.x(), masks.bounds.max.y(), masks.bounds.max.z());
  return fb::CreateTree(fbb, name, source_hash, options, &lo, &hi, static_cast<uint8_t>(depth), tree.triangle_count,
                        tree.vertex_count, levels_offset);
}

}  // namespace

std::vector<uint8_t> encode_file(std::span<const TreeToEncode> trees, const std::string& baker_version,
                                 int threads) {
  assert(!trees.empty());
  assert(threads >= 1);
  threads = std::max(threads, 1);
#ifndef NDEBUG
  std::set<std::string> names;
  for (const TreeToEncode& t : trees) assert(names.insert(t.name).second && "tree names must be unique");
#endif
  // Every field written, even when it equals its default, so the layout does
  // not depend on the values.
  flatbuffers::FlatBufferBuilder fbb(4096);
  fbb.ForceDefaults(true);
  CCtxPtr cctx(ZSTD_createCCtx(), ZSTD_freeCCtx);
  if (!cctx) throw std::bad_alloc();
  std::vector<flatbuffers::Offset<fb::Tree>> offsets;
  offsets.reserve(trees.size());
  for (const TreeToEncode& t : trees) offsets.push_back(encode_tree(fbb, cctx.get(), t, threads));
  const auto trees_offset = fbb.CreateVector(offsets);
  const auto version = fbb.CreateString(baker_version);
  fb::FinishSizePrefixedFileBuffer(fbb, fb::CreateFile(fbb, kFormatVersion, version, trees_offset));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

int encode_threads_useful(std::span<const TreeToEncode> trees) {
  size_t most = 1;
  for (const TreeToEncode& t : trees) {
    if (t.options.compression != Compression::zstd) continue;
    size_t singles = 0;
    for (const std::vector<uint8_t>& raw : t.masks.masks) {
      const bool split = split_in_jobs(raw.size());
      singles += !split;
      most = std::max({most, singles, split ? job_count(raw.size()) : 1});
    }
  }
  return int(std::min(most, size_t(256)));
}

}  // namespace octbake
