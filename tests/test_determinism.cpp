// The whole solver (Simulation from make_simulation on a scene text) gives
// bitwise-identical results on 1 and on 2 OpenMP threads: particle
// positions, displacements, velocities, stresses and volumes, every energy,
// the multimaterial counters and the reaction forces after 30 steps.
//
// Tolerance: none (memcmp of the values). Resolution: every scene but the
// two small ones at the end has more than 8192 particles and more than
// 8192 grid nodes, so that every parallel region of the solver (which
// switch on at kParallelMin = 8192 and below) really runs on 2 threads:
// 2D scenes 110 x 90 cells of 1 mm (10101 nodes) with 12000-19200
// particles (2 per cell and direction); the 3D scene 24 x 22 x 22 cells
// (13225 nodes) with 13824 particles. The initial velocity field is
// non-uniform (so stresses build up at once) and fast enough (~0.5-1 cell
// in 30 steps) that particles change tiles and the solver re-sorts them.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/multimaterial.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"
#include "test_util.hpp"

namespace {

using namespace mmpm;
using mmpm_test::BoxScene2D;

constexpr int kSteps = 30;

struct RunResult {
  std::string instantiation;
  std::size_t particles = 0, nodes = 0;
  std::vector<std::vector<double>> fields;  // kFields order
  // output.grid_fields at the end: a serial scatter, so equal bits need the
  // particles in the same order with either thread count
  std::vector<mmpm::io::ParticleField> grid;
  std::vector<double> initial_position;
  Energies energies;
  StepCounters counters;
  std::vector<Reaction> reactions;
  double time = 0;
  long steps = 0;
};

const char* const kFields[] = {"position", "displacement", "velocity", "stress", "volume"};

// A smooth, non-uniform velocity field on top of a drift (mm/ms).
std::vector<double> velocity_field(const std::vector<double>& x, int dim, double drift) {
  const std::size_t n = x.size() / std::size_t(dim);
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < n; ++p) {
    const double* xp = &x[p * std::size_t(dim)];
    v[p * dim + 0] = drift + 8.0 * std::sin(xp[1] / 5.0);
    v[p * dim + 1] = 0.5 * drift + 6.0 * std::cos(xp[0] / 7.0);
    if (dim == 3) v[p * dim + 2] = -0.3 * drift + 5.0 * std::sin((xp[0] + xp[1]) / 6.0);
  }
  return v;
}

// What a run leaves, recorded after its last step.
void record_end(const Simulation& sim, RunResult& r) {
  for (const char* f : kFields) r.fields.push_back(sim.particle_field(f).values);
  r.grid = sim.grid_snapshot({"mass", "momentum", "velocity", "force"}).fields;
  r.energies = sim.energies();
  r.counters = sim.counters();
  r.reactions = sim.reactions();
  r.time = sim.time();
  r.steps = sim.step_count();
}

RunResult run(const std::string& text, int threads, double drift) {
  omp_set_num_threads(threads);
  EXPECT_EQ(omp_get_max_threads(), threads);
  const Scene scene = parse_scene_text(text, "determinism.toml");
  std::unique_ptr<Simulation> sim = make_simulation(scene);
  RunResult r;
  r.instantiation = sim->instantiation();
  r.particles = sim->particle_count();
  r.nodes = sim->node_count();
  const int dim = scene.simulation.dimension;
  r.initial_position = sim->particle_field("position").values;
  sim->set_particle_field("velocity", velocity_field(r.initial_position, dim, drift));
  for (int s = 0; s < kSteps; ++s) sim->step();
  record_end(*sim, r);
  return r;
}

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

void expect_identical(const RunResult& a, const RunResult& b) {
  ASSERT_EQ(a.particles, b.particles);
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (std::size_t f = 0; f < a.fields.size(); ++f) {
    const auto& u = a.fields[f];
    const auto& v = b.fields[f];
    ASSERT_EQ(u.size(), v.size()) << kFields[f];
    std::size_t first = u.size(), count = 0;
    for (std::size_t i = 0; i < u.size(); ++i)
      if (!same_bits(u[i], v[i])) {
        if (first == u.size()) first = i;
        ++count;
      }
    EXPECT_EQ(count, 0u) << kFields[f] << ": " << count << " values differ, first at " << first
                         << ": " << (first < u.size() ? u[first] : 0.0) << " (1 thread) vs "
                         << (first < u.size() ? v[first] : 0.0) << " (2 threads)";
  }
  ASSERT_EQ(a.grid.size(), b.grid.size());
  EXPECT_GE(a.grid.size(), 4u);
  for (std::size_t q = 0; q < a.grid.size(); ++q) {
    ASSERT_EQ(a.grid[q].name, b.grid[q].name);
    ASSERT_EQ(a.grid[q].values.size(), b.grid[q].values.size()) << a.grid[q].name;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.grid[q].values.size(); ++i)
      differ += same_bits(a.grid[q].values[i], b.grid[q].values[i]) ? 0 : 1;
    EXPECT_EQ(differ, 0u) << "grid " << a.grid[q].name;
  }
  const Energies& e = a.energies;
  const Energies& g = b.energies;
  EXPECT_TRUE(same_bits(e.kinetic, g.kinetic)) << e.kinetic << " vs " << g.kinetic;
  EXPECT_TRUE(same_bits(e.strain, g.strain)) << e.strain << " vs " << g.strain;
  EXPECT_TRUE(same_bits(e.interface, g.interface)) << e.interface << " vs " << g.interface;
  EXPECT_TRUE(same_bits(e.external_work, g.external_work))
      << e.external_work << " vs " << g.external_work;
  EXPECT_TRUE(same_bits(e.damping, g.damping)) << e.damping << " vs " << g.damping;
  EXPECT_TRUE(same_bits(e.kinetic_unresolved, g.kinetic_unresolved))
      << e.kinetic_unresolved << " vs " << g.kinetic_unresolved;
  EXPECT_EQ(a.counters.multimaterial_nodes, b.counters.multimaterial_nodes);
  EXPECT_EQ(a.counters.nodes_3plus, b.counters.nodes_3plus);
  EXPECT_EQ(a.counters.force_limited_nodes, b.counters.force_limited_nodes);
  ASSERT_EQ(a.reactions.size(), b.reactions.size());
  for (std::size_t k = 0; k < a.reactions.size(); ++k)
    for (int d = 0; d < 3; ++d)
      EXPECT_TRUE(same_bits(a.reactions[k].force[d], b.reactions[k].force[d]))
          << "reaction " << a.reactions[k].name << " component " << d;
  EXPECT_TRUE(same_bits(a.time, b.time));
  EXPECT_EQ(a.steps, b.steps);
}

// Runs the scene on 1 and on 2 threads and compares; returns the 1-thread run
// for scene-specific sanity checks (the scene really exercised something).
// The sizes are the caller's to check (check_scene; the small scenes below).
RunResult check_runs(const std::string& text, const std::string& instantiation, double drift) {
  const int saved = omp_get_max_threads();
  const RunResult one = run(text, 1, drift);
  const RunResult two = run(text, 2, drift);
  omp_set_num_threads(saved);
  EXPECT_EQ(one.instantiation, instantiation);
  EXPECT_EQ(one.steps, kSteps);
  expect_identical(one, two);
  // Something happened: particles moved by a fair part of a cell, stresses built up.
  double max_move = 0, max_stress = 0;
  for (std::size_t i = 0; i < one.fields[0].size(); ++i)
    max_move = std::max(max_move, std::abs(one.fields[0][i] - one.initial_position[i]));
  for (double s : one.fields[3]) max_stress = std::max(max_stress, std::abs(s));
  EXPECT_GT(max_move, 0.3) << "particles should cross cells (and tiles) during the run";
  EXPECT_GT(max_stress, 0.0);
  EXPECT_GT(one.energies.strain, 0.0);
  return one;
}

// check_runs on a scene large enough for every parallel region.
RunResult check_scene(const std::string& text, const std::string& instantiation, double drift) {
  const RunResult one = check_runs(text, instantiation, drift);
  EXPECT_GT(one.particles, 8192u) << "too few particles for the parallel regions to switch on";
  EXPECT_GT(one.nodes, 8192u) << "too few nodes for the parallel regions to switch on";
  return one;
}

// Replaces the first `from` in text by `to` (a scene variant).
void replace_once(std::string& text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// (a) One material, traction on the top face, gravity, a fixed plane.
BoxScene2D single_material(const std::string& precision) {
  BoxScene2D s;
  s.precision = precision;
  s.b0_min[0] = 4, s.b0_min[1] = 4, s.b0_max[0] = 64, s.b0_max[1] = 54;  // 12000 particles
  s.extra =
      "[[boundary]]\nwhere = { y = 4.0 }\nfix = [\"y\"]\n\n"
      "[[load]]\nkind = \"traction\"\nwhere = { body = \"left\", face = \"y_max\" }\n"
      "traction = [0.5, -2.0]\nramp = 0.004\n\n"
      "[[load]]\nkind = \"gravity\"\nacceleration = [0.0, -10.0]\n";
  return s;
}

// Two materials side by side (left: a, right: b), 14400 particles, with `interaction`.
BoxScene2D two_materials(const std::string& precision, const std::string& interaction) {
  BoxScene2D s;
  s.precision = precision;
  s.two_bodies = true;
  s.second_material = true;
  s.b0_min[0] = 4, s.b0_min[1] = 4, s.b0_max[0] = 34, s.b0_max[1] = 64;
  s.b1_min[0] = 34, s.b1_min[1] = 4, s.b1_max[0] = 64, s.b1_max[1] = 64;
  s.extra = "[[interaction]]\nmaterials = [\"a\", \"b\"]\n" + interaction + "\n";
  return s;
}

const char* const kPerfectNormalInterface =
    "law = \"interface\"\nDn = \"perfect\"\nDt = 5.0\nnormal = \"specified\"\nnormal_vector = "
    "[1.0, 0.0]\n";
const char* const kNumericInterface =
    "law = \"interface\"\nDn = 200.0\nDt = 5.0\nnormal = \"specified\"\nnormal_vector = [1.0, "
    "0.0]\n";
const char* const kFrictionContact =
    "law = \"friction\"\nfriction = 0.3\nseparation = \"position\"\nnormal = \"mvg\"\n";

TEST(Determinism, SingleMaterialGimp2DTractionGravity) {
  const RunResult r = check_scene(single_material("double").text(), "2D gimp double", 40.0);
  // The body drifts up against the downward traction and gravity: negative work.
  EXPECT_LT(r.energies.external_work, 0.0);
  EXPECT_EQ(r.counters.multimaterial_nodes, 0);
}

TEST(Determinism, SingleMaterialGimp2DFloat) {
  check_scene(single_material("float").text(), "2D gimp float", 40.0);
}

TEST(Determinism, SingleMaterialLinear2DUSF) {
  BoxScene2D s = single_material("double");
  s.shape = "linear";
  s.scheme = "USF";
  check_scene(s.text(), "2D linear double", 40.0);
}

// XPIC(3) ([simulation] xpic_order): three interpolations to the
// particles and two colored scatters more per step (kernels/xpic.hpp), on
// one material and on two in frictionless contact (two velocity fields).
std::string with_xpic3(std::string text) {
  const std::string section = "[simulation]\n";
  return text.replace(text.find(section), section.size(), section + "xpic_order = 3\n");
}

TEST(Determinism, SingleMaterialGimp2DXpic) {
  check_scene(with_xpic3(single_material("double").text()), "2D gimp double", 40.0);
}

TEST(Determinism, FrictionContactGimp2DXpic) {
  check_scene(with_xpic3(two_materials("double", kFrictionContact).text()), "2D gimp double", 40.0);
}

// The plane y = 4 under the body is a mirror with B-splines
// (kernels/mirror_supports.hpp): its folds and ghost velocities are serial.
TEST(Determinism, SingleMaterialBSpline2DMirrorSupport) {
  BoxScene2D s = single_material("double");
  s.shape = "bspline2";
  check_scene(s.text(), "2D bspline2 double", 40.0);
}

// An interface crossing a mirror (the plane y = 4 under both bodies) with
// B-splines: the image's mx, Omega and g fold into the partners on the team
// (Stepper::fold_mirrors_multimaterial), the ghosts' tiles join
// p2g_multimaterial's reach, and the mvg normals read the mirror's side
// rule at the plane (docs/contact_validation.md §22).
TEST(Determinism, ImperfectInterfaceAcrossAMirrorBSpline2D) {
  BoxScene2D s =
      two_materials("double", "law = \"interface\"\nDn = 200.0\nDt = 5.0\nnormal = \"mvg\"\n");
  s.shape = "bspline2";
  s.extra += "[[boundary]]\nwhere = { y = 4.0 }\nfix = [\"y\"]\n";
  const RunResult r = check_scene(s.text(), "2D bspline2 double", 40.0);
  EXPECT_GT(r.energies.interface, 0.0);
}

TEST(Determinism, ImperfectInterfacePerfectNormal2D) {
  // Bodies 80 cells tall: the interface's ~160 multimaterial nodes reach
  // kParallelNodes, so the multimaterial passes run on the team (60 cells
  // give 124 nodes, which one thread takes).
  BoxScene2D s = two_materials("double", kPerfectNormalInterface);
  s.b0_max[1] = s.b1_max[1] = 84;
  const RunResult r = check_scene(s.text(), "2D gimp double", 40.0);
  EXPECT_GE(r.counters.multimaterial_nodes, long(kParallelNodes))
      << "the multimaterial passes must run on two threads";
}

// USL with linear shapes: light nodes (m_L = 0.5 m_p at cfl 0.5), whose
// left-out force pass B moves where it sticks the pair and the supports
// take where they fix an axis (kernels/mm_left_out.hpp, light_nodes.hpp);
// the bodies start a quarter cell off the grid lines, so light nodes lie
// along the interface, the fixed bottom and the loaded top.
// The two bodies above, a quarter cell off the grid lines, a fixed bottom,
// the left one pushed right and down by traction and gravity.
BoxScene2D usl_linear_light_nodes(const char* interaction) {
  BoxScene2D s = two_materials("double", interaction);
  s.shape = "linear";
  s.b0_min[1] = s.b1_min[1] = 4.25;
  s.b0_max[1] = s.b1_max[1] = 84.25;
  s.b0_min[0] = 4.25;
  s.b1_max[0] = 64.25;
  s.b0_max[0] = s.b1_min[0] = 34.25;
  s.extra +=
      "[[boundary]]\nwhere = { min = [-1.0, -1.0], max = [200.0, 4.5] }\nfix = [\"x\", \"y\"]\n\n"
      "[[load]]\nkind = \"traction\"\nwhere = { body = \"left\", face = \"y_max\" }\n"
      "traction = [0.5, -2.0]\nramp = 0.004\n\n"
      "[[load]]\nkind = \"gravity\"\nacceleration = [0.0, -10.0]\n";
  return s;
}

TEST(Determinism, ImperfectInterfaceUslLinearLightNodes2D) {
  const RunResult r =
      check_scene(usl_linear_light_nodes(kPerfectNormalInterface).text(), "2D linear double", 40.0);
  EXPECT_GE(r.counters.multimaterial_nodes, long(kParallelNodes));
  EXPECT_GT(r.energies.interface, 0.0);
}

// The same bodies in Coulomb contact, pressed together and sliding past
// each other (relative velocity 10 mm/ms into the face, 20 along it): pass
// B's sliding pairs exchange the light nodes' left-out normal force with its
// friction (exchange_left_out): 512-1023 exchanges over the runs at cfl 0.7
// (counted with a temporary print).
TEST(Determinism, FrictionContactUslLinearSlidingLightNodes2D) {
  BoxScene2D s = usl_linear_light_nodes(kFrictionContact);
  s.b0_vel[0] = 5.0, s.b0_vel[1] = -10.0;
  s.b1_vel[0] = -5.0, s.b1_vel[1] = 10.0;
  s.cfl = 0.7;  // m_L = 0.98 m_p: more light nodes
  const RunResult r = check_scene(s.text(), "2D linear double", 40.0);
  EXPECT_GE(r.counters.multimaterial_nodes, long(kParallelNodes));
}

TEST(Determinism, ImperfectInterfaceNumericDnMUSL2D) {
  BoxScene2D s = two_materials("double", kNumericInterface);
  s.scheme = "MUSL";
  const RunResult r = check_scene(s.text(), "2D gimp double", 40.0);
  EXPECT_GT(r.counters.multimaterial_nodes, 0);
  EXPECT_GT(r.energies.interface, 0.0)
      << "a compliant interface stores energy once it opens or slides";
}

// The largest tile edges the default picks (64 in 2D on grids from 513^2
// cells; 32 from 353^2), here forced on the 110 x 90 grid: 4 and 12
// tiles, so one color holds one tile (one thread idle) or a few, and the
// fused tail's per-thread L block holds up to 64^2 cells of particles.
TEST(Determinism, ImperfectInterfaceLargeTiles2D) {
  for (const char* edge : {"32", "64"}) {
    SCOPED_TRACE(std::string("tile ") + edge);
    BoxScene2D s = two_materials("double", kNumericInterface);
    s.scheme = "MUSL";  // the fused tail
    std::string text = s.text();
    replace_once(text, "[grid]\n", std::string("[grid]\ntile = ") + edge + "\n");
    EXPECT_EQ(make_simulation(parse_scene_text(text, "tiles.toml"))->tile_edge(), std::stoi(edge));
    const RunResult r = check_scene(text, "2D gimp double", 40.0);
    EXPECT_GT(r.counters.multimaterial_nodes, 0);
    EXPECT_GT(r.counters.p2g_from_tail, 0) << "the fused tail must have run";
  }
}

// separation = "extrapolated" (kernels/separation_extrapolation.hpp): its
// moments are scattered color by color and each node is corrected on its own.
TEST(Determinism, ImperfectInterfaceExtrapolatedSeparation2D) {
  BoxScene2D s =
      two_materials("double", std::string(kNumericInterface) + "separation = \"extrapolated\"\n");
  s.scheme = "MUSL";
  const RunResult r = check_scene(s.text(), "2D gimp double", 40.0);
  EXPECT_GT(r.counters.multimaterial_nodes, 0);
  EXPECT_GT(r.energies.interface, 0.0);
}

// area = "closed" (docs/multimaterial.md §7.1): g scattered for a specified
// normal, each node's domains closed on their own.
TEST(Determinism, ImperfectInterfaceClosedArea2D) {
  BoxScene2D s = two_materials("double", std::string(kNumericInterface) + "area = \"closed\"\n");
  s.scheme = "MUSL";
  const RunResult r = check_scene(s.text(), "2D gimp double", 40.0);
  EXPECT_GT(r.counters.multimaterial_nodes, 0);
  EXPECT_GT(r.energies.interface, 0.0);
}

// area = "gradient" (docs/multimaterial.md §7.2), the B-splines' default: g
// scattered for a specified normal, quadratic B-splines, float.
TEST(Determinism, ImperfectInterfaceGradientAreaBSpline2DFloat) {
  BoxScene2D s = two_materials("float", std::string(kNumericInterface));
  s.shape = "bspline2";
  s.scheme = "MUSL";
  const RunResult r = check_scene(s.text(), "2D bspline2 float", 40.0);
  EXPECT_GT(r.counters.multimaterial_nodes, 0);
  EXPECT_GT(r.energies.interface, 0.0);
}

// The bilinear law's perfect compression branch, one-sided (docs/multimaterial.md
// §4.1), decided in pass A and again in pass B: the blocks pushed into each other.
TEST(Determinism, ImperfectInterfaceBilinearPerfectCompression2D) {
  BoxScene2D s =
      two_materials("double", std::string(kNumericInterface) + "traction_law = \"bilinear\"\n");
  s.scheme = "MUSL";
  s.b0_vel[0] = 30.0;
  s.b1_vel[0] = -30.0;
  const RunResult r = check_scene(s.text(), "2D gimp double", 40.0);
  EXPECT_GT(r.counters.multimaterial_nodes, 0);
}

TEST(Determinism, ImperfectInterfaceFloat2D) {
  const RunResult r =
      check_scene(two_materials("float", kNumericInterface).text(), "2D gimp float", 40.0);
  EXPECT_GT(r.counters.multimaterial_nodes, 0);
}

// A scene, as parsed, stepped `steps` times on `threads` threads.
RunResult run_parsed(const Scene& scene, int threads, int steps) {
  omp_set_num_threads(threads);
  auto sim = make_simulation(scene);
  RunResult r;
  r.instantiation = sim->instantiation();
  r.particles = sim->particle_count();
  r.nodes = sim->node_count();
  r.initial_position = sim->particle_field("position").values;
  for (int k = 0; k < steps; ++k) sim->step();
  record_end(*sim, r);
  return r;
}

// Two blocks driven into each other through Coulomb contact, under `scheme`.
void check_friction_contact(const std::string& scheme) {
  BoxScene2D s = two_materials("double", kFrictionContact);
  s.scheme = scheme;
  // Leave a gap of one particle spacing less than a cell between the blocks.
  s.b1_min[0] = 34.5;
  s.b1_max[0] = 64.5;
  s.b0_vel[0] = 30.0, s.b0_vel[1] = 10.0;
  s.b1_vel[0] = -30.0, s.b1_vel[1] = -10.0;
  // The scene's own body velocities make them approach; drift 0 keeps them.
  const Scene scene = parse_scene_text(s.text(), "contact.toml");
  const int saved = omp_get_max_threads();
  const RunResult one = run_parsed(scene, 1, kSteps), two = run_parsed(scene, 2, kSteps);
  omp_set_num_threads(saved);
  EXPECT_EQ(one.instantiation, "2D gimp double");
  EXPECT_GT(one.particles, 8192u);
  EXPECT_GT(one.nodes, 8192u);
  EXPECT_GT(one.counters.multimaterial_nodes, 0) << "the blocks must be in contact";
  EXPECT_GT(one.energies.strain, 0.0) << "contact must have stressed the blocks";
  expect_identical(one, two);
}

TEST(Determinism, FrictionContactTwoBlocksApproaching2D) {
  check_friction_contact("USL");
}

// USF carries the last pass B's held and stuck pairs into the next pass A
// (docs/contact_validation.md §13).
TEST(Determinism, FrictionContactTwoBlocksApproachingUSF2D) {
  check_friction_contact("USF");
}

// normal = "geometry" turns the floor's and the block's gradients to their
// boxes before pass A, the block's carried by the motion fitted to its
// particles (solver/geometry_normals.hpp): the block slides down the
// incline of inputs/rotated_incline.toml the same, bit for bit, on 1 and
// 2 threads (1000 steps: past the gravity ramp, sliding).
TEST(Determinism, RotatedInclineGeometryNormal2D) {
  const Scene scene =
      parse_scene_file(mmpm_test::source_dir() + "/inputs/rotated_incline.toml", {});
  const int saved = omp_get_max_threads();
  const RunResult one = run_parsed(scene, 1, 1000), two = run_parsed(scene, 2, 1000);
  omp_set_num_threads(saved);
  EXPECT_GT(one.counters.multimaterial_nodes, 0) << "the block must be on the floor";
  expect_identical(one, two);
}

// The half Hertz disk on the symmetry plane x = 12 (tests/test_validation_hertz.cpp):
// the multimaterial nodes on the plane drop their gradients' x components
// (kernels/support_gradients.hpp, a serial pass) and the plane mirrors the
// disk. 600 steps (0.2 ms, the disk pressing into the floor under its
// ramping weight), bit for bit the same on 1 and 2 threads.
TEST(Determinism, HalfHertzDiskOnASymmetryPlane2D) {
  const std::string file = mmpm_test::source_dir() + "/inputs/hertz_disk.toml";
  const Scene scene = parse_scene_text(
      mmpm_test::read_text(file) + "\n[[boundary]]\nwhere = { x = 12.0 }\nfix = [\"x\"]\n", file,
      {"body[0].min=[12.0,1.0]", "body[1].clip={min=[12.0,0.0],max=[24.0,24.0]}"});
  const int saved = omp_get_max_threads();
  const RunResult one = run_parsed(scene, 1, 600), two = run_parsed(scene, 2, 600);
  omp_set_num_threads(saved);
  EXPECT_GT(one.particles, 8192u) << "too few particles for the parallel regions to switch on";
  EXPECT_GT(one.nodes, 8192u) << "too few nodes for the parallel regions to switch on";
  EXPECT_GT(one.counters.multimaterial_nodes, 0) << "the disk must be on the floor";
  EXPECT_GT(one.energies.strain, 0.0);
  expect_identical(one, two);
}

std::string scene_3d() {
  return R"(
[simulation]
dimension = 3
end_time = 1.0
cfl = 0.5

[grid]
origin = [0.0, 0.0, 0.0]
cell = [1.0, 1.0, 1.0]
cells = [24, 22, 22]
shape = "gimp"

[[material]]
name = "a"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.3

[[body]]
name = "cube"
material = "a"
shape = "box"
min = [3.0, 3.0, 3.0]
max = [15.0, 15.0, 15.0]
particles_per_cell = 2

[[boundary]]
where = { z = 3.0 }
fix = ["z"]

[[load]]
kind = "traction"
where = { body = "cube", face = "z_max" }
traction = [0.3, 0.0, -1.5]
ramp = 0.004

[[load]]
kind = "gravity"
acceleration = [0.0, 0.0, -10.0]
)";
}

// Small scenes, where the thresholds of the parallel regions decide what
// runs on the team (Stepper::particles_on_team, kParallelMinNodes,
// kNodeReduceChunk; docs/performance.md "Node loops of small grids, and
// particle passes by their work"): check_runs, with the sizes asserted to
// sit in the regime each scene is for.

// 2D uGIMP, two materials joined by an imperfect interface, grid damping:
// 6240 particles (below 8192, above uGIMP's 3641: the particle passes on
// the team) and 61 x 41 nodes x 2 fields = 5002 (between 4096 and 8192: the
// node loops on the team, the damped update summed in 1024-node chunks, 3
// per field, shared by the two threads).
TEST(Determinism, SmallDampedInterfaceGimp2D) {
  BoxScene2D s = two_materials("double", kNumericInterface);
  s.cells_x = 60, s.cells_y = 40;
  s.b0_min[0] = 4, s.b0_min[1] = 4, s.b0_max[0] = 34, s.b0_max[1] = 34;
  s.b1_min[0] = 34, s.b1_min[1] = 4, s.b1_max[0] = 56, s.b1_max[1] = 34;
  std::string text = s.text();
  // The first is the [grid] table's (the bodies' shape is "box").
  replace_once(text, "shape = \"gimp\"\n\n", "shape = \"gimp\"\ndamping = 25.0\n\n");
  const RunResult r = check_runs(text, "2D gimp double", 40.0);
  EXPECT_EQ(r.particles, 6240u);
  EXPECT_EQ(r.nodes, 2501u);
  EXPECT_GT(r.energies.damping, 0.0) << "the damped update's sum must have run";
}

// 3D uGIMP, 4096 particles (above 3D uGIMP's 1214: the particle passes on
// the team) on 15^3 = 3375 nodes of one field (below 4096: the node loops
// on one thread, after passes on two).
TEST(Determinism, SmallGimp3D) {
  std::string text = scene_3d();
  replace_once(text, "cells = [24, 22, 22]", "cells = [14, 14, 14]");
  replace_once(text, "max = [15.0, 15.0, 15.0]", "max = [11.0, 11.0, 11.0]");
  const RunResult r = check_runs(text, "3D gimp double", 40.0);
  EXPECT_EQ(r.particles, 4096u);
  EXPECT_EQ(r.nodes, 3375u);
}

TEST(Determinism, Gimp3DTractionGravity) {
  const RunResult r = check_scene(scene_3d(), "3D gimp double", 40.0);
  // The cube drifts down (z) with the downward traction and gravity: positive work.
  EXPECT_GT(r.energies.external_work, 0.0);
}

}  // namespace
