// libFuzzer: any bytes given to BakedFile::from_bytes, then every tree loaded
// at its full depth, must give a value or an Error and never crash, leak or
// hit undefined behaviour. A successful load must nest.
//
// Build (clang; instrument the runtime too so coverage guides the fuzzer):
//   CXX=clang++ CXXFLAGS=-fsanitize=fuzzer-no-link cmake -S . -B build-fuzz \
//     -DOCTBAKE_FUZZ=ON -DOCTBAKE_BUILD_TESTS=OFF -DOCTBAKE_SANITIZE=ON
//   cmake --build build-fuzz --target fuzz_baked_file
//   mkdir -p corpus && cp tests/golden/*.oct corpus/
//   build-fuzz/tests/fuzz_baked_file corpus -max_total_time=120
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "octbake/baked_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // A private copy: from_bytes keeps a view, and the copy lets ASan see reads
  // one past the end.
  const std::vector<uint8_t> bytes(data, data + size);
  octbake::Result<octbake::BakedFile> file = octbake::BakedFile::from_bytes(bytes, "fuzz");
  if (!file) return 0;
  for (size_t i = 0; i < file->trees().size(); ++i) {
    octbake::Result<octbake::ObjectTree> tree = file->load(i, file->trees()[i].depth);
    if (!tree) continue;
    // The loaded masks must agree with the header at every depth.
    const octbake::OctreeMasks& masks = tree->masks();
    uint64_t boxes = 1;
    for (int d = 0; d < masks.depth(); ++d) {
      if (masks.masks[d].size() != boxes || tree->info().box_count[d] != boxes) std::abort();
      boxes = 0;
      for (uint8_t m : masks.masks[d]) boxes += std::popcount(m);
    }
    if (tree->info().box_count[masks.depth()] != boxes) std::abort();
  }
  return 0;
}
