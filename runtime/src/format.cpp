// encode_file(): TreeToEncode -> the bytes of schema/octbake.fbs, always the
// newest format version (kFormatVersion). Its readers, one per version, are
// beside it in baked_file.cpp (BakedFile::Impl::verify / decode_level).
#include "octbake/format.h"

#include <zstd.h>

#include <algorithm>
#include <cassert>
#include <memory>
#include <new>
#include <set>

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
constexpr size_t kJobsPerLevel = 8;  // enough to balance a few threads
// Each job is primed with the last 1/16 of a window of the job before it (512
// KiB at level 19): most of the long matches for a few percent of size.
// Priming costs about what compressing the same bytes does, so a full-window
// overlap would double the work.
constexpr int kOverlapLog = 5;

// Depends on the level's size only, never on the threads.
size_t job_size(size_t raw) { return std::clamp((raw + kJobsPerLevel - 1) / kJobsPerLevel, kMinJob, kMaxJob); }

size_t job_count(size_t raw) { return raw <= kMinJob ? 1 : (raw + job_size(raw) - 1) / job_size(raw); }

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

flatbuffers::Offset<fb::Tree> encode_tree(flatbuffers::FlatBufferBuilder& fbb, ZSTD_CCtx* cctx,
                                          const TreeToEncode& tree, int threads) {
  const OctreeMasks& masks = tree.masks;
  const int depth = masks.depth();
  assert(depth == tree.options.depth && depth >= 1 && depth <= kMaxDepth);
  assert(!tree.name.empty());
  assert(masks.bounds.min.allFinite() && masks.bounds.max.allFinite());
  assert((masks.bounds.min.array() <= masks.bounds.max.array()).all());

  std::vector<flatbuffers::Offset<fb::Level>> levels;
  levels.push_back(fb::CreateLevel(fbb, /*box_count=*/1, /*raw_size=*/0, fb::Compression::None,
                                   fbb.CreateVector(std::vector<uint8_t>{})));
  for (int d = 1; d <= depth; ++d) {
    const std::vector<uint8_t>& raw = masks.masks[d - 1];
    assert(raw.size() == masks.box_count(d - 1));
    fb::Compression stored = fb::Compression::None;
    flatbuffers::Offset<flatbuffers::Vector<uint8_t>> data;
    if (tree.options.compression == Compression::zstd) {
      std::vector<uint8_t> frame = zstd_frame(cctx, raw, tree.options.compression_level, threads);
      if (frame.size() < raw.size()) {
        stored = fb::Compression::Zstd;
        data = fbb.CreateVector(frame);
      }
    }
    if (stored == fb::Compression::None) data = fbb.CreateVector(raw);
    levels.push_back(fb::CreateLevel(fbb, masks.box_count(d), raw.size(), stored, data));
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
  if (!zstd_has_threads()) return 1;
  size_t most = 1;
  for (const TreeToEncode& t : trees)
    if (t.options.compression == Compression::zstd)
      for (const std::vector<uint8_t>& raw : t.masks.masks) most = std::max(most, job_count(raw.size()));
  return int(std::min(most, size_t(256)));
}

}  // namespace octbake
