// Grid fields on request (SCENE.md, "run.h5 — particle snapshots, grid
// fields on request"): `[output] grid_fields` writes /grid/step_*/<quantity>
// with every particle snapshot, and run_grid.xdmf to open them in ParaView.
//
// What the quantities must be, whatever the shape functions: the nodal
// values of a P2G of the particles as they are at the snapshot (ALGORITHM
// §1-2), so
//   - the shape functions are a partition of unity: Σ_i m_i = Σ_p m_p and
//     Σ_i p_i = Σ_p m_p v_p;
//   - their gradients sum to zero: Σ_i f_i = Σ_p f_ext,p (the internal
//     forces cancel), here 0;
//   - a body moving at one velocity v has p_i / m_i = v at every node it
//     reaches.
// Tolerances: 1e-12 relative (sums of ~10^3 doubles), 1e-9 of Σ|f| for the
// force sum. Scenes: inputs/bar_vibration.toml (400 particles, 54 x 6
// cells, uGIMP, v = 0.5 mm/ms, a fixed end), inputs/collision.toml with
// its blocks touching (two materials at +4 and -2 mm/ms, each its own
// velocity field), a 3D box.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "io/h5.hpp"
#include "test_util.hpp"

namespace {

using namespace mmpm_test;
namespace h5 = mmpm::io::h5;

double sum_of(const std::vector<double>& v, int components, int c) {
  double s = 0;
  for (std::size_t i = std::size_t(c); i < v.size(); i += std::size_t(components)) s += v[i];
  return s;
}

double abs_sum_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += std::abs(x);
  return s;
}

struct Snap {
  std::vector<double> particle_mass, particle_velocity;  // velocity: D per particle
  std::map<std::string, std::vector<double>> grid;
  std::map<std::string, std::vector<hsize_t>> shape;
};

std::vector<Snap> read_snapshots(const fs::path& file) {
  const h5::File f = h5::File::open(file, h5::File::Mode::read_only);
  const h5::Group root = f.root();
  const h5::Group particles = root.open_group("particles");
  const h5::Group grid = root.open_group("grid");
  std::vector<Snap> out;
  for (const std::string& name : particles.children()) {
    Snap s;
    const h5::Group p = particles.open_group(name);
    s.particle_mass = p.open_dataset("mass").read_doubles();
    s.particle_velocity = p.open_dataset("velocity").read_doubles();
    const h5::Group g = grid.open_group(name);  // the same step's grid
    for (const std::string& q : g.children()) {
      s.grid[q] = g.open_dataset(q).read_doubles();
      s.shape[q] = g.open_dataset(q).shape();
    }
    out.push_back(std::move(s));
  }
  return out;
}

void expect_sums_match(const Snap& s, int D, const std::string& suffix = "") {
  const double m = sum_of(s.particle_mass, 1, 0);
  EXPECT_NEAR(sum_of(s.grid.at("mass" + suffix), 1, 0), m, 1e-12 * m);
  for (int d = 0; d < D; ++d) {
    double mv = 0, mv_abs = 0;
    for (std::size_t p = 0; p < s.particle_mass.size(); ++p) {
      mv += s.particle_mass[p] * s.particle_velocity[p * std::size_t(D) + std::size_t(d)];
      mv_abs +=
          std::abs(s.particle_mass[p] * s.particle_velocity[p * std::size_t(D) + std::size_t(d)]);
    }
    EXPECT_NEAR(sum_of(s.grid.at("momentum" + suffix), D, d), mv, 1e-12 * mv_abs + 1e-300)
        << "axis " << d;
  }
}

TEST(GridOutput, SingleMaterialSumsMatchTheParticles) {
  TempDir tmp;
  const fs::path out = tmp / "bar";
  const CmdResult r = run_mmpm({"run", source_dir() + "/inputs/bar_vibration.toml", "--set",
                                "simulation.end_time=0.05", "--set", "output.every=0.025", "--set",
                                R"(output.fields=["velocity", "mass"])", "--set",
                                R"(output.grid_fields=["mass", "momentum", "velocity", "force"])",
                                "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const std::vector<Snap> snaps = read_snapshots(out / "run.h5");
  ASSERT_GE(snaps.size(), 3u);  // t = 0, 0.025, 0.05 (and the last step's state)
  for (const Snap& s : snaps) {
    ASSERT_EQ(s.grid.size(), 4u) << "one field: no per-field datasets";
    EXPECT_EQ(s.shape.at("mass"), (std::vector<hsize_t>{7, 55, 1}));  // ny, nx, components
    EXPECT_EQ(s.shape.at("velocity"), (std::vector<hsize_t>{7, 55, 2}));
    expect_sums_match(s, 2);
    const std::vector<double>& f = s.grid.at("force");
    for (int d = 0; d < 2; ++d)
      EXPECT_NEAR(sum_of(f, 2, d), 0.0, 1e-9 * abs_sum_of(f) + 1e-300) << "axis " << d;
  }
  // At t = 0 the bar moves at 0.5 mm/ms, stress-free.
  const Snap& first = snaps.front();
  const std::vector<double>& m = first.grid.at("mass");
  const std::vector<double>& v = first.grid.at("velocity");
  int reached = 0;
  for (std::size_t n = 0; n < m.size(); ++n) {
    if (m[n] <= 1e-9 * first.particle_mass[0]) {
      EXPECT_EQ(v[2 * n], 0.0);
      continue;
    }
    ++reached;
    EXPECT_NEAR(v[2 * n], 0.5, 1e-12);
    EXPECT_NEAR(v[2 * n + 1], 0.0, 1e-12);
  }
  EXPECT_GT(reached, 150);  // 51 x 3 nodes under the 25 x 1 mm bar and more with uGIMP
  EXPECT_EQ(abs_sum_of(first.grid.at("force")), 0.0);
  // Later the bar is strained: the internal forces are not all zero.
  EXPECT_GT(abs_sum_of(snaps.back().grid.at("force")), 0.0);

  const std::string xdmf = read_text(out / "run_grid.xdmf");
  EXPECT_TRUE(contains(xdmf, R"(TopologyType="3DCoRectMesh" Dimensions="1 7 55")")) << xdmf;
  EXPECT_TRUE(contains(xdmf, "run.h5:/xdmf_grid/step_")) << "2D vectors padded to 3";
  EXPECT_TRUE(contains(xdmf, "run.h5:/grid/step_")) << xdmf;
}

TEST(GridOutput, PerFieldQuantitiesInMultimaterialScenes) {
  TempDir tmp;
  const fs::path out = tmp / "collision";
  const CmdResult r = run_mmpm(
      {"run", source_dir() + "/inputs/collision.toml", "--set", "body[1].min=[12.0, 2.0]", "--set",
       "simulation.end_time=0.01", "--set", "output.every=0.01", "--set",
       R"(output.fields=["velocity", "mass", "material"])", "--set",
       R"(output.grid_fields=["mass", "momentum", "velocity"])", "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const std::vector<Snap> snaps = read_snapshots(out / "run.h5");
  ASSERT_GE(snaps.size(), 1u);
  const Snap& s = snaps.front();  // t = 0: block a at +4, block b at -2 mm/ms
  for (const char* q : {"mass", "momentum", "velocity"})
    for (const char* field : {"", ".block_a", ".block_b"})
      EXPECT_TRUE(s.grid.count(std::string(q) + field)) << q << field;
  expect_sums_match(s, 2);
  const std::vector<double>& ma = s.grid.at("mass.block_a");
  const std::vector<double>& mb = s.grid.at("mass.block_b");
  const std::vector<double>& m = s.grid.at("mass");
  const std::vector<double>& va = s.grid.at("velocity.block_a");
  const std::vector<double>& vb = s.grid.at("velocity.block_b");
  const std::vector<double>& v = s.grid.at("velocity");
  int shared = 0;
  for (std::size_t n = 0; n < m.size(); ++n) {
    EXPECT_EQ(m[n], ma[n] + mb[n]);
    const double tiny = 1e-9 * s.particle_mass[0];
    if (ma[n] > tiny) {
      EXPECT_NEAR(va[2 * n], 4.0, 1e-12);
    }
    if (mb[n] > tiny) {
      EXPECT_NEAR(vb[2 * n], -2.0, 1e-12);
    }
    if (ma[n] > tiny && mb[n] > tiny) {
      ++shared;  // the centre-of-mass velocity of both fields
      EXPECT_NEAR(v[2 * n], (4.0 * ma[n] - 2.0 * mb[n]) / m[n], 1e-12);
    }
  }
  EXPECT_GT(shared, 0) << "block b moved to touch block a: their stencils share nodes";
  // Each field's mass is its material's.
  const h5::File f = h5::File::open(out / "run.h5", h5::File::Mode::read_only);
  const std::string first = f.root().open_group("particles").children().front();
  const std::vector<double> material =
      f.root().open_group("particles").open_group(first).open_dataset("material").read_doubles();
  double mass_a = 0;
  for (std::size_t p = 0; p < material.size(); ++p)
    if (material[p] == 0.0) mass_a += s.particle_mass[p];
  EXPECT_NEAR(sum_of(ma, 1, 0), mass_a, 1e-12 * mass_a);
}

TEST(GridOutput, ThreeDimensionalGrid) {
  TempDir tmp;
  const fs::path scene = tmp / "box.toml";
  write_text(scene, R"([simulation]
dimension = 3
end_time = 0.01
cfl = 0.4

[grid]
origin = [0.0, 0.0, 0.0]
cell = [1.0, 1.0, 1.0]
cells = [6, 5, 4]
shape = "gimp"

[[material]]
name = "steel"
type = "isotropic"
density = 7.8e-3
E = 200000.0
nu = 0.3

[[body]]
name = "box"
material = "steel"
shape = "box"
min = [1.0, 1.0, 1.0]
max = [5.0, 4.0, 3.0]
particles_per_cell = 2
velocity = [0.0, 0.0, 0.3]

[output]
every = 0.01
fields = ["velocity", "mass"]
grid_fields = ["mass", "momentum", "velocity"]
)");
  const fs::path out = tmp / "o";
  const CmdResult r = run_mmpm({"run", scene.string(), "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const std::vector<Snap> snaps = read_snapshots(out / "run.h5");
  ASSERT_GE(snaps.size(), 2u);
  for (const Snap& s : snaps) {
    EXPECT_EQ(s.shape.at("mass"), (std::vector<hsize_t>{5, 6, 7, 1}));  // nz, ny, nx
    EXPECT_EQ(s.shape.at("velocity"), (std::vector<hsize_t>{5, 6, 7, 3}));
    expect_sums_match(s, 3);
  }
  const std::vector<double>& m = snaps.front().grid.at("mass");
  const std::vector<double>& v = snaps.front().grid.at("velocity");
  for (std::size_t n = 0; n < m.size(); ++n)
    if (m[n] > 1e-9 * snaps.front().particle_mass[0]) {
      EXPECT_NEAR(v[3 * n + 2], 0.3, 1e-12);
    }
  const std::string xdmf = read_text(out / "run_grid.xdmf");
  EXPECT_TRUE(contains(xdmf, R"(TopologyType="3DCoRectMesh" Dimensions="5 6 7")")) << xdmf;
}

// An unknown quantity is bad input: exit 2, one line naming the key and
// listing the quantities; without grid_fields no /grid and no run_grid.xdmf.
TEST(GridOutput, UnknownQuantityIsBadInputAndNoneIsTheDefault) {
  TempDir tmp;
  const CmdResult bad = run_mmpm({"check", source_dir() + "/inputs/bar_vibration.toml", "--set",
                                  R"(output.grid_fields=["mass", "temperature"])"});
  EXPECT_EQ(bad.exit_code, 2) << bad.describe();
  EXPECT_EQ(lines_of(bad.err).size(), 1u) << bad.err;
  EXPECT_TRUE(contains(bad.err, "'output.grid_fields'")) << bad.err;
  EXPECT_TRUE(contains(bad.err, "\"temperature\"")) << bad.err;
  EXPECT_TRUE(contains(bad.err, "velocity")) << bad.err;

  const fs::path out = tmp / "plain";
  const CmdResult r = run_mmpm({"run", source_dir() + "/inputs/bar_vibration.toml", "--set",
                                "simulation.end_time=0.01", "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  EXPECT_FALSE(fs::exists(out / "run_grid.xdmf"));
  const h5::File f = h5::File::open(out / "run.h5", h5::File::Mode::read_only);
  EXPECT_FALSE(f.root().contains("grid"));
}

}  // namespace
