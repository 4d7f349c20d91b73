// SPDX-License-Identifier: AGPL-3.0-or-later
#include "samples.hpp"

#include <cmath>

namespace hmc::samples {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

Mesh uv_sphere(int rings, int segments, double radius) {
  Mesh m;
  m.points.push_back({0, 0, radius});
  for (int r = 1; r < rings; ++r) {
    double th = kPi * r / rings;
    for (int s = 0; s < segments; ++s) {
      double ph = 2 * kPi * s / segments;
      m.points.push_back({radius * std::sin(th) * std::cos(ph), radius * std::sin(th) * std::sin(ph),
                          radius * std::cos(th)});
    }
  }
  m.points.push_back({0, 0, -radius});
  auto idx = [&](int r, int s) { return static_cast<std::uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  const auto south = static_cast<std::uint32_t>(m.points.size() - 1);
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, idx(1, s), idx(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({idx(r, s), idx(r + 1, s), idx(r + 1, s + 1)});
      m.triangles.push_back({idx(r, s), idx(r + 1, s + 1), idx(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({idx(rings - 1, s), south, idx(rings - 1, s + 1)});
  return m;
}

Mesh torus(int nu, int nv, double major, double minor) {
  Mesh m;
  for (int i = 0; i < nu; ++i) {
    double u = 2 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      double v = 2 * kPi * j / nv;
      double rr = major + minor * std::cos(v);
      m.points.push_back({rr * std::cos(u), rr * std::sin(u), minor * std::sin(v)});
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

Mesh height_field(int n, double amplitude) {
  Mesh m;
  std::mt19937 rng(7);  // the tests' figures depend on this sequence
  std::uniform_real_distribution<double> jitter(-0.25, 0.25);
  const double c = std::cos(0.4), s = std::sin(0.4);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double u = (i + jitter(rng)) / (n - 1), v = (j + jitter(rng)) / (n - 1);
      m.points.push_back({c * u - s * v, s * u + c * v, amplitude * std::sin(5.0 * u + 1.0) * std::cos(4.0 * v - 0.5)});
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * n + j); };
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

Mesh random_ball(std::size_t n, std::uint64_t seed, double radius) {
  Rng rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mesh m;
  while (m.points.size() < n) {
    double x = u(rng), y = u(rng), z = u(rng);
    if (x * x + y * y + z * z <= 1.0) m.points.push_back({radius * x, radius * y, radius * z});
  }
  return m;
}

Mesh layered_ball(const std::vector<int>& counts) {
  Mesh m;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  const auto shells = static_cast<double>(counts.size());
  for (std::size_t s = 0; s < counts.size(); ++s) {
    const double r = (shells - static_cast<double>(s)) / shells;
    const int n = counts[s];
    if (n == 1) {
      m.points.push_back({0, 0, 0});
      continue;
    }
    for (int i = 0; i < n; ++i) {
      const double z = 1 - 2 * (i + 0.5) / n, rho = std::sqrt(1 - z * z), phi = golden * i + 0.7 * static_cast<double>(s);
      m.points.push_back({r * rho * std::cos(phi), r * rho * std::sin(phi), r * z});
    }
  }
  return m;
}

Mesh random_sphere_points(std::size_t n, std::uint64_t seed, double radius) {
  Rng rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Mesh m;
  while (m.points.size() < n) {
    double x = g(rng), y = g(rng), z = g(rng);
    double r = std::sqrt(x * x + y * y + z * z);
    if (r > 1e-9) m.points.push_back({radius * x / r, radius * y / r, radius * z / r});
  }
  return m;
}

Mesh lattice(int nx, int ny, int nz, double h) {
  Mesh m;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) m.points.push_back({i * h, j * h, k * h});
  return m;
}

Mesh clustered(int clusters, int per, std::uint64_t seed) {
  Rng rng(seed);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  std::normal_distribution<double> g(0.0, 0.2);
  Mesh m;
  for (int c = 0; c < clusters; ++c) {
    double cx = u(rng), cy = u(rng), cz = u(rng);
    for (int i = 0; i < per; ++i) m.points.push_back({cx + g(rng), cy + g(rng), cz + g(rng)});
  }
  return m;
}

Mesh coplanar(std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mesh m;
  for (std::size_t i = 0; i < n; ++i) {
    double x = u(rng), y = u(rng);
    m.points.push_back({x, y, 0.3 * x - 0.2 * y + 1.0});
  }
  return m;
}

Mesh collinear(std::size_t n, std::uint64_t seed) {
  Rng rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Mesh m;
  for (std::size_t i = 0; i < n; ++i) {
    double t = u(rng);
    m.points.push_back({1.0 + 2.0 * t, -1.0 + t, 0.5 - 3.0 * t});
  }
  return m;
}

Mesh all_duplicates(std::size_t n) {
  Mesh m;
  m.points.assign(n, Vec3{0.25, -3.5, 7.0});
  return m;
}

}  // namespace hmc::samples
