#include "bench_data.hpp"
#include "rgbl/place/scan_context.hpp"

#include <benchmark/benchmark.h>

namespace {

// Two scans 25 frames (~34 m) apart: a distant pair, the common case when a database is queried.
void scan_context_compare_rgbl(benchmark::State& state) {
  const rgbl::ScanContext a = rgbl::make_scan_context(rgbl::bench::scan(0));
  const rgbl::ScanContext b = rgbl::make_scan_context(rgbl::bench::scan(25));
  for (auto _ : state) benchmark::DoNotOptimize(rgbl::compare(a, b));
}

// The exhaustive search over every column shift, compare()'s reference.
void scan_context_compare_reference(benchmark::State& state) {
  const rgbl::ScanContext a = rgbl::make_scan_context(rgbl::bench::scan(0));
  const rgbl::ScanContext b = rgbl::make_scan_context(rgbl::bench::scan(25));
  for (auto _ : state) benchmark::DoNotOptimize(rgbl::compare_all_shifts(a, b));
}

}  // namespace

BENCHMARK(scan_context_compare_rgbl)->Name("scan_context_compare/rgbl")->Unit(benchmark::kMicrosecond);
BENCHMARK(scan_context_compare_reference)->Name("scan_context_compare/reference")->Unit(benchmark::kMicrosecond);
