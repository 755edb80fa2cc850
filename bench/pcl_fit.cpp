// probeloop_bench_pcl FILE [--reps N] [--budget SECONDS]
// The same point file through PCL: SampleConsensusModelSphere / SampleConsensusModelCylinder
// ::optimizeModelCoefficients (Eigen Levenberg-Marquardt with a numerical Jacobian, in
// float) from the start stored in the file, i.e. the start probeloop's fit gets. All points
// are inliers. The cylinder model is given the exact normals of the generating cylinder
// (stored in the file); optimizeModelCoefficients itself does not read them.
// Times only the optimizeModelCoefficients call (steady_clock and process CPU time), repeated up to N times
// (default 5) or until the budget (default 3 s) is spent, at least once; prints JSON with
// every time, the median and the fitted parameters.
#include <pcl/pcl_config.h>
#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/sac_model_cylinder.h>
#include <pcl/sample_consensus/sac_model_sphere.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>
#include <vector>

#include "bench/bench_data.hpp"

namespace {

using probeloop::bench::DataKind;
using probeloop::bench::DataSet;

double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Times {
  std::vector<double> real_s, cpu_s;
};

template <typename Model>
Times timeOptimize(const Model& model, const pcl::Indices& inliers, const Eigen::VectorXf& start,
                   Eigen::VectorXf& result, int reps, double budget_s) {
  Times times;
  double spent = 0.0;
  while (static_cast<int>(times.real_s.size()) < reps && (times.real_s.empty() || spent < budget_s)) {
    Eigen::VectorXf out;
    const double c0 = processCpuSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    model.optimizeModelCoefficients(inliers, start, out);
    const auto t1 = std::chrono::steady_clock::now();
    const double c1 = processCpuSeconds();
    const double s = std::chrono::duration<double>(t1 - t0).count();
    times.real_s.push_back(s);
    times.cpu_s.push_back(c1 - c0);
    spent += s;
    result = out;
  }
  return times;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FILE [--reps N] [--budget SECONDS]\n", argv[0]);
    return 2;
  }
  int reps = 5;
  double budget_s = 3.0;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--reps") reps = std::atoi(argv[i + 1]);
    else if (flag == "--budget") budget_s = std::atof(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  try {
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
    const DataSet d = probeloop::bench::readDataSet(argv[1]);
    const std::size_t n = d.points.size();
    auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = d.points[i];
      (*cloud)[i] = pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(p.z()));
    }
    pcl::Indices inliers(n);
    std::iota(inliers.begin(), inliers.end(), 0);

    nlohmann::ordered_json out;
    out["tool"] = "pcl";
    out["version"] = PCL_VERSION_PRETTY;
    out["file"] = argv[1];
    out["n"] = n;
    Eigen::VectorXf result;
    Times times;
    if (d.kind == DataKind::Sphere) {
      Eigen::VectorXf start(4);
      start << static_cast<float>(d.start.position.x()), static_cast<float>(d.start.position.y()),
          static_cast<float>(d.start.position.z()), static_cast<float>(d.start.radius);
      pcl::SampleConsensusModelSphere<pcl::PointXYZ> model(cloud);
      times = timeOptimize(model, inliers, start, result, reps, budget_s);
      out["kind"] = "sphere";
      out["params"] = {{"position_mm", {result[0], result[1], result[2]}},
                       {"radius_mm", result[3]}};
    } else if (d.kind == DataKind::Cylinder) {
      if (d.normals.size() != n) throw std::runtime_error("cylinder file without normals");
      auto normals = pcl::make_shared<pcl::PointCloud<pcl::Normal>>();
      normals->resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        const auto& v = d.normals[i];
        (*normals)[i] = pcl::Normal(static_cast<float>(v.x()), static_cast<float>(v.y()),
                                    static_cast<float>(v.z()));
      }
      Eigen::VectorXf start(7);
      for (int k = 0; k < 3; ++k) {
        start[k] = static_cast<float>(d.start.position[k]);
        start[3 + k] = static_cast<float>(d.start.direction[k]);
      }
      start[6] = static_cast<float>(d.start.radius);
      pcl::SampleConsensusModelCylinder<pcl::PointXYZ, pcl::Normal> model(cloud);
      model.setInputNormals(normals);
      times = timeOptimize(model, inliers, start, result, reps, budget_s);
      out["kind"] = "cylinder";
      out["params"] = {{"position_mm", {result[0], result[1], result[2]}},
                       {"direction", {result[3], result[4], result[5]}},
                       {"radius_mm", result[6]}};
    } else {
      throw std::runtime_error("PCL harness handles sphere and cylinder files only");
    }
    out["times_s"] = times.real_s;
    out["median_s"] = median(times.real_s);
    out["cpu_times_s"] = times.cpu_s;
    out["median_cpu_s"] = median(times.cpu_s);
    std::cout << out.dump() << "\n";
  } catch (const std::exception& e) {
    std::fprintf(stderr, "probeloop_bench_pcl: %s\n", e.what());
    return 1;
  }
  return 0;
}
