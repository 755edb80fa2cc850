// probeloop_bench_fit --data_dir=DIR [--fits_out=FILE] [--max_ls=N] [--max_mz=N]
//                     [Google Benchmark flags]
// Times probeloop's fits on the point files written by probeloop_bench_data:
//   ReadPass/n      one plain pass summing the coordinates of the plane points (reference)
//   LS_Plane/n, LS_Sphere/n, LS_Cylinder/n        n = 1e3 .. 1e7
//   MZ_Roundness/n (circle2d), MZ_Flatness/n (plane)  n = 1e2 .. 1e5
// Reports real time and process CPU time (every fitter here is single-threaded; on a
// shared machine the CPU time is the steadier of the two).
// The cylinder (and sphere) fits get the start stored in the file, the same start the PCL
// and SciPy harnesses use. --fits_out writes the fitted parameters of every benchmark (one
// untimed fit per data set) as JSON, for the agreement columns of the report.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/bench_data.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/minimum_zone.hpp"

namespace {

using probeloop::bench::DataKind;
using probeloop::bench::DataSet;
namespace geo = probeloop::geometry;

std::string g_data_dir;
nlohmann::ordered_json g_fits = nlohmann::ordered_json::object();

// One data set in memory at a time: benchmarks are registered grouped by file.
const DataSet& dataSet(DataKind kind, std::size_t n) {
  static std::string loaded;
  static std::unique_ptr<DataSet> data;
  const std::string path =
      g_data_dir + "/" + probeloop::bench::dataKindName(kind) + "_" + std::to_string(n) + ".bin";
  if (loaded != path) {
    data.reset();
    data = std::make_unique<DataSet>(probeloop::bench::readDataSet(path));
    loaded = path;
  }
  return *data;
}

geo::Element startElement(geo::ElementKind kind, const DataSet& d) {
  geo::Element e;
  e.kind = kind;
  e.position_mm = d.start.position;
  e.direction = d.start.direction;
  e.radius_mm = d.start.radius;
  return e;
}

nlohmann::ordered_json describe(const geo::FitResult& r) {
  const auto& e = r.element;
  return {{"kind", std::string(geo::elementName(e.kind))},
          {"method", std::string(geo::methodName(r.method))},
          {"position_mm", {e.position_mm.x(), e.position_mm.y(), e.position_mm.z()}},
          {"direction", {e.direction.x(), e.direction.y(), e.direction.z()}},
          {"radius_mm", e.radius_mm},
          {"rms_mm", r.rms_mm},
          {"form_mm", r.form_mm},
          {"iterations", r.iterations},
          {"support_points", r.support_points.size()}};
}

struct Case {
  std::string name;  // e.g. "LS_Sphere/1000000"
  DataKind data;
  geo::ElementKind element;
  bool minimum_zone;
  std::size_t n;
};

void runFit(benchmark::State& state, const Case& c) {
  const DataSet& d = dataSet(c.data, c.n);
  geo::LeastSquaresOptions options;
  // Parameters and residual statistics (ssr, rms, form), as the peers give: no per-point
  // residual vector (one more pass and n doubles written when asked for).
  options.keep_residuals = false;
  if (c.element == geo::ElementKind::Cylinder || c.element == geo::ElementKind::Sphere)
    options.start = startElement(c.element, d);
  auto fit = [&] {
    return c.minimum_zone ? geo::fitMinimumZone(c.element, d.points)
                          : geo::fitLeastSquares(c.element, d.points, options);
  };
  // One untimed fit per data set: records the parameters, and a fitter that throws is
  // reported as an error instead of a time.
  if (!g_fits.contains(c.name)) {
    try {
      auto entry = describe(fit());
      if (c.minimum_zone) {  // the LS peak-to-valley of the same data, for comparison
        const auto ls = geo::fitLeastSquares(c.element, d.points);
        entry["ls_form_mm"] = ls.form_mm;
      }
      g_fits[c.name] = entry;
    } catch (const std::exception& e) {
      g_fits[c.name] = {{"error", e.what()}};
    }
  }
  if (g_fits[c.name].contains("error")) {
    state.SkipWithError(g_fits[c.name]["error"].get<std::string>().c_str());
    return;
  }
  int iterations = 0;
  for (auto _ : state) {
    auto r = fit();
    benchmark::DoNotOptimize(r.element);
    iterations = r.iterations;
  }
  state.counters["points"] = static_cast<double>(c.n);
  state.counters["fit_iterations"] = iterations;
}

void runReadPass(benchmark::State& state, std::size_t n) {
  const auto& pts = dataSet(DataKind::Plane, n).points;
  for (auto _ : state) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& p : pts) sum += p;
    benchmark::DoNotOptimize(sum);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(n * sizeof(Eigen::Vector3d)));
  state.counters["points"] = static_cast<double>(n);
}

std::vector<Case>& cases() {
  static std::vector<Case> all;  // stable addresses for the registered lambdas
  return all;
}

void registerAll(std::size_t max_ls, std::size_t max_mz) {
  auto& all = cases();
  std::vector<std::size_t> ls_sizes, mz_sizes;
  for (std::size_t n = 1000; n <= max_ls; n *= 10) ls_sizes.push_back(n);
  for (std::size_t n = 100; n <= max_mz; n *= 10) mz_sizes.push_back(n);
  for (std::size_t n : ls_sizes) all.push_back({"LS_Plane/" + std::to_string(n), DataKind::Plane,
                                                geo::ElementKind::Plane, false, n});
  for (std::size_t n : ls_sizes) all.push_back({"LS_Sphere/" + std::to_string(n), DataKind::Sphere,
                                                geo::ElementKind::Sphere, false, n});
  for (std::size_t n : ls_sizes)
    all.push_back({"LS_Cylinder/" + std::to_string(n), DataKind::Cylinder,
                   geo::ElementKind::Cylinder, false, n});
  for (std::size_t n : mz_sizes)
    all.push_back({"MZ_Roundness/" + std::to_string(n), DataKind::Roundness,
                   geo::ElementKind::Circle2D, true, n});
  for (std::size_t n : mz_sizes)
    all.push_back({"MZ_Flatness/" + std::to_string(n), DataKind::Flatness,
                   geo::ElementKind::Plane, true, n});

  for (const Case& c : all) {
    if (c.data == DataKind::Plane) {  // the read pass right before the plane fit, same vector
      const std::size_t n = c.n;
      benchmark::RegisterBenchmark(("ReadPass/" + std::to_string(n)).c_str(),
                                   [n](benchmark::State& s) { runReadPass(s, n); })
          ->Unit(benchmark::kMillisecond)
          ->MeasureProcessCPUTime()
          ->UseRealTime();
    }
    const Case* cp = &c;
    benchmark::RegisterBenchmark(c.name.c_str(), [cp](benchmark::State& s) { runFit(s, *cp); })
        ->Unit(benchmark::kMillisecond)
        ->MeasureProcessCPUTime()
        ->UseRealTime();
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::string fits_out;
  std::size_t max_ls = 10'000'000, max_mz = 100'000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* flag) -> const char* {
      const std::string f = std::string(flag) + "=";
      return a.rfind(f, 0) == 0 ? argv[i] + f.size() : nullptr;
    };
    if (const char* v = value("--data_dir")) g_data_dir = v;
    else if (const char* v = value("--fits_out")) fits_out = v;
    else if (const char* v = value("--max_ls")) max_ls = std::strtoull(v, nullptr, 10);
    else if (const char* v = value("--max_mz")) max_mz = std::strtoull(v, nullptr, 10);
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (g_data_dir.empty()) {
    std::fprintf(stderr, "usage: %s --data_dir=DIR [--fits_out=FILE] [--max_ls=N] [--max_mz=N]\n",
                 argv[0]);
    return 2;
  }
  registerAll(max_ls, max_mz);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (!fits_out.empty()) {
    std::ofstream out(fits_out);
    out << g_fits.dump(1) << "\n";
    if (!out) {
      std::fprintf(stderr, "cannot write %s\n", fits_out.c_str());
      return 1;
    }
  }
  return 0;
}
