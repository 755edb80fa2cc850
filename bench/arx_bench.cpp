// ARX identification speed and coefficients (issue 5 item 8): writes the data set it fits
// (bench/results/arx_data.csv) so an independent implementation can fit the same numbers,
// then times fitArx (median of REPS) and prints the coefficients as JSON.
// Data: 72 h at 5 min (864 samples) of 6 random-step inputs, ARX with na = 1 and nb = 3 per
// input (19 parameters with the intercept) plus white equation error.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "model/arx.hpp"

using namespace probeloop;

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "bench/results/arx_data.csv";
  const int N = 864, r = 6, reps = 51;
  std::mt19937 g(42);
  std::uniform_real_distribution<double> level(0, 5);
  std::uniform_int_distribution<int> hold(3, 24);
  std::normal_distribution<double> e(0, 0.05);
  Eigen::MatrixXd u(N, r);
  for (int i = 0; i < r; ++i) {
    double v = level(g);
    for (int k = 0, left = hold(g); k < N; ++k, --left) {
      if (left == 0) v = level(g), left = hold(g);
      u(k, i) = v;
    }
  }
  Eigen::VectorXd y = Eigen::VectorXd::Zero(N);
  for (int k = 2; k < N; ++k) {
    double v = 0.3 + 0.85 * y(k - 1) + e(g);
    for (int i = 0; i < r; ++i) v += (0.4 - 0.1 * i) * u(k, i) + (0.2 + 0.05 * i) * u(k - 1, i) - 0.15 * u(k - 2, i);
    y(k) = v;
  }
  std::ofstream f(out);
  f << "y";
  for (int i = 0; i < r; ++i) f << ",u" << i + 1;
  f << "\n";
  f.precision(17);
  for (int k = 0; k < N; ++k) {
    f << y(k);
    for (int i = 0; i < r; ++i) f << "," << u(k, i);
    f << "\n";
  }
  model::ArxOrders o;
  o.na = 1;
  o.nb.assign(r, 3);
  o.intercept = true;
  std::vector<double> t;
  model::ArxModel m;
  for (int rep = 0; rep < reps; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    m = model::fitArx(y, u, o);
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  std::printf("{\"seconds\": %.9f, \"theta\": {", t[t.size() / 2]);
  for (Eigen::Index i = 0; i < m.theta.size(); ++i)
    std::printf("%s\"%s\": %.17g", i ? ", " : "", m.names[static_cast<std::size_t>(i)].c_str(), m.theta(i));
  std::printf("}, \"u\": {");
  for (Eigen::Index i = 0; i < m.theta.size(); ++i)
    std::printf("%s\"%s\": %.17g", i ? ", " : "", m.names[static_cast<std::size_t>(i)].c_str(), std::sqrt(m.covariance(i, i)));
  std::printf("}}\n");
  return 0;
}
