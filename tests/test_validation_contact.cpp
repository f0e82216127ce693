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
struct Stats { double m = 0, x = 0, y = 0, vx = 0, vy = 0, Lz = 0, I = 0; };
Stats body_stats(const Simulation& sim, int material) {
  const auto v = field(sim, "velocity"), m = field(sim, "mass"), mat = field(sim, "material"), x = field(sim, "position");
  Stats s;
  for (std::size_t p = 0; p < sim.particle_count(); ++p) {
    if (int(mat.at(p)) != material) continue;
    s.m += m.at(p); s.x += m.at(p) * x.at(p, 0); s.y += m.at(p) * x.at(p, 1);
    s.vx += m.at(p) * v.at(p, 0); s.vy += m.at(p) * v.at(p, 1);
  }
  s.x /= s.m; s.y /= s.m; s.vx /= s.m; s.vy /= s.m;
  for (std::size_t p = 0; p < sim.particle_count(); ++p) {
    if (int(mat.at(p)) != material) continue;
    const double rx = x.at(p, 0) - s.x, ry = x.at(p, 1) - s.y;
    s.Lz += m.at(p) * (rx * (v.at(p, 1) - s.vy) - ry * (v.at(p, 0) - s.vx));
    s.I += m.at(p) * (rx * rx + ry * ry);
  }
  return s;
}
double slope(const std::vector<double>& t, const std::vector<double>& y) {
  double st = 0, sy = 0, stt = 0, sty = 0; const double n = double(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) { st += t[k]; sy += y[k]; stt += t[k] * t[k]; sty += t[k] * y[k]; }
  return (n * sty - st * sy) / (n * stt - st * st);
}
TEST(ContactExplore, Incline) {
  const char* scene = std::getenv("SCENE") ? std::getenv("SCENE") : MMPM_SOURCE_DIR "/inputs/incline_block.toml";
  std::vector<std::string> ov;
  if (const char* e = std::getenv("OVS")) {
    std::string all = e; std::size_t pos = 0;
    while (pos <= all.size()) { auto q = all.find(';', pos); if (q == std::string::npos) q = all.size(); if (q > pos) ov.push_back(all.substr(pos, q - pos)); pos = q + 1; }
  }
  const Scene sc = parse_scene_file(scene, ov);
  auto sim = make_simulation(sc);
  const double G = std::hypot(sc.loads[0].acceleration[0], sc.loads[0].acceleration[1]);
  const double th = std::atan2(sc.loads[0].acceleration[0], -sc.loads[0].acceleration[1]);
  const double mu = sc.interactions[0].friction;
  int mat = 0; for (std::size_t m = 0; m < sc.materials.size(); ++m) if (sc.materials[m].type != MaterialType::rigid) mat = int(m);
  const double tend = std::getenv("TEND") ? atof(std::getenv("TEND")) : sc.simulation.end_time;
  const double t0 = std::getenv("T0") ? atof(std::getenv("T0")) : 0.3 * tend;
  std::vector<double> ts, vs, xs, ws, rx, ry;
  const Stats s0 = body_stats(*sim, mat);
  int k = 0;
  while (sim->time() < tend) {
    sim->step(); ++k;
    const Stats s = body_stats(*sim, mat);
    Vec3 r{0, 0, 0};
    for (const auto& q : sim->reactions()) if (q.name.rfind("rigid:", 0) == 0) r = q.force;
    if (sim->time() >= t0) { ts.push_back(sim->time()); vs.push_back(s.vx); xs.push_back(s.x - s0.x); ws.push_back(s.Lz / s.I); rx.push_back(r[0]); ry.push_back(r[1]); }
    if (k % 50 == 0) printf("t %.4f x %.5f y %.5f vx %.5f vy %.5f omega %.4f R %.4g %.4g mm %ld\n", sim->time(), s.x - s0.x, s.y - s0.y, s.vx, s.vy, s.Lz / s.I, r[0], r[1], sim->counters().multimaterial_nodes);
  }
  const double a = slope(ts, vs);
  double mrx = 0, mry = 0; for (std::size_t i = 0; i < rx.size(); ++i) { mrx += rx[i]; mry += ry[i]; } mrx /= rx.size(); mry /= ry.size();
  const double slide = G * (std::sin(th) - mu * std::cos(th)), roll = 2.0 / 3.0 * G * std::sin(th);
  printf("G %.3f theta %.2f mu %.3f mass %.5g: a_fit %.4f slide %.4f (%.4f) roll %.4f (%.4f); mean R %.5g %.5g vs weight n %.5g t_slide %.5g t_stick %.5g; omega/v*? %.4f\n",
         G, th * 180 / M_PI, mu, s0.m, a, slide, a / slide, roll, a / roll, mrx, mry, -s0.m * G * std::cos(th), s0.m * mu * G * std::cos(th), s0.m * G * std::sin(th), slope(ts, ws) / a);
}
}  // namespace
}  // namespace mmpm
