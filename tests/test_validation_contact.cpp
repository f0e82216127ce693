#include <gtest/gtest.h>
#include <cstdio>
#include "tests/validation_util.hpp"
namespace mmpm {
namespace {
using testing::field;

struct Body { double m = 0, px = 0, py = 0, x = 0, y = 0, maxx = -1e9, minx = 1e9; };

TEST(ContactExplore, Collision) {
  const char* law = std::getenv("LAW") ? std::getenv("LAW") : "frictionless";
  const char* nrm = std::getenv("NRM") ? std::getenv("NRM") : "avg";
  std::vector<std::string> ov = {std::string("interaction[0].law=\"") + law + "\"",
                                 std::string("interaction[0].normal=\"") + nrm + "\""};
  if (const char* e = std::getenv("OVS")) {
    std::string all = e; std::size_t pos = 0;
    while (pos <= all.size()) { auto q = all.find(';', pos); if (q == std::string::npos) q = all.size(); if (q > pos) ov.push_back(all.substr(pos, q - pos)); pos = q + 1; }
  }
  auto sim = make_simulation(parse_scene_file(std::getenv("SCENE") ? std::getenv("SCENE") : MMPM_SOURCE_DIR "/inputs/collision.toml", std::getenv("SCENE") ? std::vector<std::string>{} : ov));
  double P0 = 0;
  double maxerr = 0;
  const double tend = std::getenv("TEND") ? atof(std::getenv("TEND")) : 0.25;
  int k = 0;
  while (sim->time() < tend) {
    const auto v = field(*sim, "velocity"), m = field(*sim, "mass"), mat = field(*sim, "material"), x = field(*sim, "position");
    Body b[2];
    double P = 0, Py = 0;
    for (std::size_t p = 0; p < sim->particle_count(); ++p) {
      int j = int(mat.at(p));
      b[j].m += m.at(p); b[j].px += m.at(p) * v.at(p, 0); b[j].py += m.at(p) * v.at(p, 1);
      b[j].x += m.at(p) * x.at(p, 0);
      b[j].maxx = std::max(b[j].maxx, x.at(p, 0)); b[j].minx = std::min(b[j].minx, x.at(p, 0));
      P += m.at(p) * v.at(p, 0); Py += m.at(p) * v.at(p, 1);
    }
    if (k == 0) P0 = P;
    maxerr = std::max(maxerr, std::abs(P - P0) / std::abs(P0));
    const auto e = sim->energies();
    if (k % 10 == 0 || std::getenv("ALL"))
      printf("t %.4f vA %.5f vB %.5f  Perr %.3e Py %.2e KE %.5f SE %.5f TOT %.5f gapAB %.4f mm %ld\n", sim->time(), b[0].px / b[0].m, b[1].px / b[1].m,
             (P - P0) / P0, Py, e.kinetic, e.strain, e.kinetic + e.strain, b[1].minx - b[0].maxx, sim->counters().multimaterial_nodes);
    sim->step();
    ++k;
  }
  printf("max perr %.3e\n", maxerr);
}
// Predict the momentum lost at nodes whose field mass is below the grid threshold.
TEST(ContactExplore, ThresholdHypothesis) {
  std::vector<std::string> ov = {"interaction[0].min_volume=0.5"};
  auto sim = make_simulation(parse_scene_file(MMPM_SOURCE_DIR "/inputs/collision.toml", ov));
  const double h = 0.5, l = 0.25, dt = sim->dt();
  auto gimp = [&](double d, double& w, double& dw) {
    const double a = std::abs(d), sgn = d < 0 ? -1 : 1;
    if (a < l) { w = 1 - (d * d + l * l) / (2 * l); dw = -d / l; }
    else if (a < 1 - l) { w = 1 - a; dw = -sgn; }
    else if (a < 1 + l) { const double q = 1 + l - a; w = q * q / (4 * l); dw = -sgn * q / (2 * l); }
    else { w = 0; dw = 0; }
  };
  double min_mass = 1e300;
  { auto m = field(*sim, "mass"); for (double v : m.values) min_mass = std::min(min_mass, v); }
  const double thr = 1e-9 * min_mass;
  double Pprev = 0;
  for (int k = 0; k < 200; ++k) {
    const auto v = field(*sim, "velocity"), m = field(*sim, "mass"), mat = field(*sim, "material"),
               x = field(*sim, "position"), s = field(*sim, "stress"), V = field(*sim, "volume");
    double P = 0;
    for (std::size_t p = 0; p < sim->particle_count(); ++p) P += m.at(p) * v.at(p, 0);
    // nodal mass and force per field on a 51 x 17 grid
    std::vector<double> nm(2 * 51 * 17, 0), fx(2 * 51 * 17, 0);
    for (std::size_t p = 0; p < sim->particle_count(); ++p) {
      const int j = int(mat.at(p));
      const double xi = x.at(p, 0) / h, yi = x.at(p, 1) / h;
      const int bx = int(std::floor(xi - 0.5)), by = int(std::floor(yi - 0.5));
      for (int a = 0; a < 3; ++a) for (int b = 0; b < 3; ++b) {
        double wx, dwx, wy, dwy;
        gimp(xi - (bx + a), wx, dwx); gimp(yi - (by + b), wy, dwy);
        const std::size_t n = std::size_t(j) * 51 * 17 + std::size_t(by + b) * 51 + std::size_t(bx + a);
        nm[n] += wx * wy * m.at(p);
        const double gx = dwx * wy / h, gy = wx * dwy / h;
        fx[n] -= V.at(p) * (s.at(p, 0) * gx + s.at(p, 2) * gy);
      }
    }
    double lost = 0; int count = 0;
    for (std::size_t n = 0; n < nm.size(); ++n) if (!(nm[n] > thr) && fx[n] != 0) { lost += fx[n] * dt; ++count; }
    sim->step();
    const auto v2 = field(*sim, "velocity"), m2 = field(*sim, "mass");
    double P2 = 0;
    for (std::size_t p = 0; p < sim->particle_count(); ++p) P2 += m2.at(p) * v2.at(p, 0);
    if (std::abs(P2 - P) > 1e-15 || count) printf("step %d dP %.3e predicted(-lost) %.3e nodes %d\n", k, P2 - P, -lost, count);
    (void)Pprev;
  }
}
}  // namespace
}  // namespace mmpm
