// --kernel=portable|avx2|avx512 for the benchmarks: measure that build of the
// box-test kernel (default: the widest the CPU has). The builds differ in
// speed only (the same hits, counts and leaf pairs), and a CPU with AVX-512
// can thus show what an AVX2-only or an ARM user gets.
//
// --shared-axis=off: test pairs that share an axis on all fifteen axes, as
// before the shortcut (use_shared_axis_shortcut): its before and after from
// one binary.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "octbake/collide.h"

namespace octbake {

// Takes every --kernel=NAME and --shared-axis=on|off out of argv (argc
// updated) and selects that kernel. False, with one error line naming
// `tool`, if NAME is unknown or this CPU cannot run it, or the shared-axis
// value is neither on nor off.
inline bool take_kernel_option(int& argc, char** argv, const char* tool) {
  int kept = 0;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (i > 0 && a.rfind("--shared-axis=", 0) == 0) {
      const std::string v = a.substr(14);
      if (v != "on" && v != "off") {
        std::fprintf(stderr, "%s: --shared-axis=%s: expected on or off\n", tool, v.c_str());
        return false;
      }
      use_shared_axis_shortcut(v == "on");
      continue;
    }
    if (i == 0 || a.rfind("--kernel=", 0) != 0) {
      argv[kept++] = argv[i];
      continue;
    }
    const std::string k = a.substr(9);
    const BoxKernel kernel = k == "portable" ? BoxKernel::portable
                             : k == "avx2"   ? BoxKernel::avx2
                             : k == "avx512" ? BoxKernel::avx512
                                             : BoxKernel::best;
    if (kernel == BoxKernel::best || !use_box_kernel(kernel)) {
      std::fprintf(stderr, "%s: --kernel=%s: not a kernel this CPU runs (portable, avx2, avx512)\n", tool, k.c_str());
      return false;
    }
  }
  argc = kept;
  return true;
}

// main() of a Google Benchmark program with --kernel: exit 2 on a bad
// --kernel or an unknown argument.
inline int run_benchmarks(int argc, char** argv, const char* tool) {
  if (!take_kernel_option(argc, argv, tool)) return 2;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace octbake
