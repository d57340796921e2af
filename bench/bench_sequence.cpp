// mbi deform on a trajectory, per frame: a 1M-point model's frame into a PC2 cache (modified-BI's
// solve, the float kernel, the cache's append) beside writing the same bytes with plain fwrite
// into the same folder (no fsync either way). scripts/bench-sequence.sh reports their ratio.
#include "bench_common.hpp"

#include <mbi/io/io.hpp>
#include <mbi/pipeline/deformer.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace {

using namespace mbi;

// A lattice of p points in the 448-vertex box cage, in order (as a mesh's vertices are: the
// kernel's coherent case), bound once.
struct Setup {
  std::unique_ptr<pipeline::Deformer> deformer;
  Eigen::MatrixXd X;
};

const Setup& setup(long long points) {
  static std::map<long long, std::unique_ptr<Setup>> cache;
  auto& slot = cache[points];
  if (slot) return *slot;
  slot = std::make_unique<Setup>();
  const bench::Cage& cage = bench::box_cage(450);
  const Eigen::Vector3d hi = bench::cage_cells(450).cast<double>();
  const long long side = static_cast<long long>(std::ceil(std::cbrt(static_cast<double>(points))));
  Eigen::MatrixXd P(points, 3);
  for (long long i = 0; i < points; ++i)
    P.row(i) = Eigen::RowVector3d((i % side + 0.5) / side * hi.x(), ((i / side) % side + 0.5) / side * hi.y(),
                                  (i / side / side + 0.5) / side * hi.z());
  slot->deformer = std::make_unique<pipeline::Deformer>(cage.U, cage.T, P);
  slot->X = cage.X;
  return *slot;
}

// Where both write: the same folder (the working directory's filesystem).
fs::path folder() { return fs::current_path(); }

// Every 16 frames the file starts over (outside the timing), so that it stays small.
constexpr int kFramesAFile = 16;

void BM_SequencePc2Frame(benchmark::State& state) {
  const long long p = state.range(0);
  const Setup& s = setup(p);
  interp::RowMatrixXf xyz(p, 3);
  const fs::path file = folder() / "bench-sequence.pc2";
  auto writer = std::make_unique<io::Pc2Writer>(file, static_cast<int>(p));
  int n = 0;
  for (auto _ : state) {
    s.deformer->deform_float(s.X, xyz);
    writer->append(xyz.data());
    if (++n % kFramesAFile == 0) {
      state.PauseTiming();
      writer = std::make_unique<io::Pc2Writer>(file, static_cast<int>(p));  // the old temporary is removed
      state.ResumeTiming();
    }
  }
  writer.reset();
  state.counters["bytes_per_frame"] = static_cast<double>(12 * p);
}

void BM_SequenceFwriteFrame(benchmark::State& state) {
  const long long p = state.range(0);
  const std::vector<float> bytes(static_cast<std::size_t>(3 * p), 0.5f);
  const fs::path file = folder() / "bench-sequence-fwrite.bin";
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (!f) return state.SkipWithError("cannot open a file in the working directory");
  int n = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(std::fwrite(bytes.data(), sizeof(float), bytes.size(), f));
    if (++n % kFramesAFile == 0) {
      state.PauseTiming();
      std::fclose(f);
      f = std::fopen(file.c_str(), "wb");  // truncated
      state.ResumeTiming();
    }
  }
  std::fclose(f);
  fs::remove(file);
  state.counters["bytes_per_frame"] = static_cast<double>(12 * p);
}

long long sequence_points() { return bench::quick() ? 35000 : 1000000; }

}  // namespace

BENCHMARK(BM_SequencePc2Frame)->ArgName("points")->Arg(sequence_points())->Unit(benchmark::kMillisecond)
    ->UseRealTime()->MinTime(mbi::bench::min_time(1.0));
BENCHMARK(BM_SequenceFwriteFrame)->ArgName("points")->Arg(sequence_points())->Unit(benchmark::kMillisecond)
    ->UseRealTime()->MinTime(mbi::bench::min_time(1.0));
