// [simulation] skip_empty_nodes (default true): the node passes visit only
// the nodes each field's particles can reach (kernels/active_nodes.hpp).
//
// 1. The run lists: clipping (FieldNodeRuns::for_each) and the set
//    difference a rebuild zeroes (for_each_dropped), against a node-by-node
//    reference on random run sets.
// 2. Coverage: after every step of scenes whose bodies move across tiles,
//    every node where a field has mass lies in that field's runs.
// 3. The skipped nodes would have computed zeros, so every particle field,
//    energy and reaction must be bitwise those of skip_empty_nodes = false,
//    step after step. Tolerance: none (bitwise). Scenes: a two-field stack
//    sliding along a floor support under gravity, fast enough to cross
//    several tiles of 4 cells (the runs are rebuilt, support nodes leave
//    and join them), on 1 and on 2 threads; every shipped scene with nodes
//    to skip (2D and the 3D sphere in a cube); USL.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bitwise_same.hpp"
#include "kernels/active_nodes.hpp"
#include "kernels/shape.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"
#include "solver/stepper.hpp"
#include "validation_util.hpp"

namespace {

using namespace mmpm;
using mmpm::testing::expect_bitwise_same;

const std::string kInputs = std::string(MMPM_SOURCE_DIR) + "/inputs/";

// Random ascending, disjoint, non-adjacent runs inside [0, nodes).
std::vector<FieldNodeRuns::Run> random_runs(std::mt19937& rng, std::uint32_t nodes) {
  std::vector<FieldNodeRuns::Run> runs;
  std::uniform_int_distribution<std::uint32_t> gap(1, 9), len(1, 12);
  std::uint32_t at = std::uniform_int_distribution<std::uint32_t>(0, 3)(rng);
  while (at < nodes) {
    const std::uint32_t end = std::min(nodes, at + len(rng));
    runs.push_back({at, end});
    at = end + gap(rng);
  }
  return runs;
}

std::vector<char> membership(const std::vector<FieldNodeRuns::Run>& runs, std::size_t nodes) {
  std::vector<char> in(nodes, 0);
  for (const auto& r : runs)
    for (std::uint32_t i = r[0]; i < r[1]; ++i) in[i] = 1;
  return in;
}

TEST(ActiveNodes, ForEachClipsTheRunsToTheRange) {
  std::mt19937 rng(7);
  const std::uint32_t nodes = 200;
  for (int trial = 0; trial < 50; ++trial) {
    FieldNodeRuns r;
    r.field.push_back(random_runs(rng, nodes));
    const std::vector<char> in = membership(r.field[0], nodes);
    std::uniform_int_distribution<std::size_t> pick(0, nodes);
    std::size_t b = pick(rng), e = pick(rng);
    if (b > e) std::swap(b, e);
    std::vector<char> seen(nodes, 0);
    std::size_t previous_end = 0;
    r.for_each(0, b, e, [&](std::size_t first, std::size_t last) {
      EXPECT_LT(first, last);
      EXPECT_GE(first, previous_end) << "runs out of order";
      previous_end = last;
      for (std::size_t i = first; i < last; ++i) seen[i] = 1;
    });
    for (std::size_t i = 0; i < nodes; ++i)
      ASSERT_EQ(seen[i], char(in[i] && i >= b && i < e)) << "trial " << trial << " node " << i;
  }
}

TEST(ActiveNodes, DroppedIsBeforeMinusAfter) {
  std::mt19937 rng(11);
  const std::uint32_t nodes = 300;
  for (int trial = 0; trial < 50; ++trial) {
    FieldNodeRuns before, after;
    for (int f = 0; f < 2; ++f) {
      before.field.push_back(random_runs(rng, nodes));
      after.field.push_back(random_runs(rng, nodes));
    }
    std::vector<std::vector<char>> dropped(2, std::vector<char>(nodes, 0));
    for_each_dropped(before, after, [&](int f, std::size_t b, std::size_t e) {
      EXPECT_LT(b, e);
      for (std::size_t i = b; i < e; ++i) {
        EXPECT_EQ(dropped[std::size_t(f)][i], 0) << "node listed twice";
        dropped[std::size_t(f)][i] = 1;
      }
    });
    for (int f = 0; f < 2; ++f) {
      const auto a = membership(before.field[std::size_t(f)], nodes);
      const auto b = membership(after.field[std::size_t(f)], nodes);
      for (std::size_t i = 0; i < nodes; ++i)
        ASSERT_EQ(dropped[std::size_t(f)][i], char(a[i] && !b[i]))
            << "trial " << trial << " field " << f << " node " << i;
    }
  }
  // The first build: every node was "active", so everything outside is dropped.
  FieldNodeRuns after;
  after.field.push_back({{10, 20}});
  std::size_t count = 0;
  for_each_dropped(all_node_runs(100, 1), after,
                   [&](int, std::size_t b, std::size_t e) { count += e - b; });
  EXPECT_EQ(count, 90u);
}

TEST(ActiveNodes, QuantileCountsOnlyTheRuns) {
  FieldNodeRuns r;
  r.field.push_back({{0, 100}});               // field 0: nodes 0 .. 99
  r.field.push_back({{50, 100}, {300, 350}});  // field 1: 100 nodes
  // 200 nodes in all: half of them lie below node 75 (75 + 25).
  EXPECT_EQ(r.node_quantile(1000, 1, 2), 75u);
  EXPECT_EQ(r.node_quantile(1000, 0, 2), 0u);
  EXPECT_EQ(r.node_quantile(1000, 2, 2), 350u);
  // A body filling the bottom quarter of the nodes: the even split of the
  // visited nodes lies inside it, not at the middle of the grid.
  FieldNodeRuns bottom;
  bottom.field.push_back({{0, 250}});
  EXPECT_EQ(bottom.node_quantile(1000, 1, 2), 125u);
}

// Two blocks of different materials stacked (frictionless contact between
// them) slide along a floor support (y fixed) under gravity at 50 mm/ms:
// about 8 mm, 16 cells, 4 tiles of 4 cells over the run, so the runs are
// rebuilt many times, and floor nodes leave and join them.
std::string sliding_stack() {
  return R"([simulation]
dimension = 2
plane     = "strain"
end_time  = 1.0
cfl       = 0.4

[grid]
origin = [-1.0, -1.0]
cell   = [0.5, 0.5]
cells  = [64, 40]
shape  = "gimp"
tile   = 4

[[material]]
name    = "lower"
type    = "isotropic"
density = 1.0e-3
E       = 10.0
nu      = 0.3

[[material]]
name    = "upper"
type    = "isotropic"
density = 1.0e-3
E       = 20.0
nu      = 0.3

[[body]]
name     = "lower"
material = "lower"
shape    = "box"
min      = [0.0, 0.0]
max      = [4.0, 2.0]
particles_per_cell = 2
velocity = [50.0, 0.0]

[[body]]
name     = "upper"
material = "upper"
shape    = "box"
min      = [0.5, 2.0]
max      = [3.5, 3.5]
particles_per_cell = 2
velocity = [50.0, 0.0]

[[interaction]]
materials  = ["lower", "upper"]
law        = "frictionless"
normal     = "avg"
separation = "position"

[[boundary]]
where = { min = [-1.0, -1.0], max = [31.0, 0.0] }
fix   = ["y"]

[[load]]
kind         = "gravity"
acceleration = [0.0, -200.0]
)";
}

// Every node where a field has mass lies in that field's runs. Returns the
// nodes (of all fields) outside the runs: the nodes the passes skip.
template <int D, class Shape, class Real>
std::size_t expect_mass_inside_runs(Simulation& sim, const std::string& what) {
  auto* stepper = dynamic_cast<Stepper<D, Shape, Real>*>(&sim);
  EXPECT_NE(stepper, nullptr) << what;
  if (!stepper) return 0;
  const NodeOwnership& own = stepper->ownership();
  EXPECT_NE(own.active, nullptr) << what << ": no runs with skip_empty_nodes = true";
  if (!own.active) return 0;
  const GridView<D, Real>& G = stepper->grid();
  for (int f = 0; f < G.fields; ++f) {
    std::vector<char> in(G.nodes, 0);
    own.active->for_each(f, 0, G.nodes, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) in[i] = 1;
    });
    std::size_t outside = 0;
    for (std::size_t i = 0; i < G.nodes; ++i)
      outside += G.m[std::size_t(f) * G.nodes + i] != Real(0) && !in[i];
    EXPECT_EQ(outside, 0u) << what << " field " << f;
  }
  return G.nodes * std::size_t(G.fields) - own.active->node_count();
}

struct Runs {
  std::unique_ptr<Simulation> skip, all;
};

// min_gap: the skip run's shortest skipped gap (0: every empty part of a
// row, which the default kMinSkippedNodes joins in grids this small).
template <int D, class Shape, class Real = double>
Runs make_both(const std::string& text, const std::string& file, std::vector<std::string> sets,
               std::size_t min_gap = 0) {
  auto scene = [&](bool skip) {
    std::vector<std::string> s = sets;
    s.push_back(std::string("simulation.skip_empty_nodes=") + (skip ? "true" : "false"));
    return file.empty() ? parse_scene_text(text, "sliding_stack.toml", s)
                        : parse_scene_file(kInputs + file, s);
  };
  Runs r{make_simulation(scene(true)), make_simulation(scene(false))};
  auto* stepper = dynamic_cast<Stepper<D, Shape, Real>*>(r.skip.get());
  EXPECT_NE(stepper, nullptr);
  if (stepper) stepper->set_min_skipped_nodes(min_gap);
  return r;
}

template <int D, class Shape, class Real = double>
void run_both(const std::string& what, Runs r, int steps, int check) {
  std::size_t skipped = 0;
  for (int s = 1; s <= steps; ++s) {
    r.skip->step();
    r.all->step();
    if (s % check == 0 || s == steps) {
      const std::string at = what + " step " + std::to_string(s);
      expect_bitwise_same(*r.skip, *r.all, at);
      skipped = std::max(skipped, expect_mass_inside_runs<D, Shape, Real>(*r.skip, at));
      if (::testing::Test::HasFailure()) break;
    }
  }
  EXPECT_GT(skipped, 0u) << what << ": no node was skipped, nothing was tested";
}

TEST(ActiveNodes, SlidingStackOnSupportBitwise) {
  const int saved = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    const std::string t = std::to_string(threads) + " threads";
    run_both<2, GimpShape>("sliding stack, every gap, " + t,
                           make_both<2, GimpShape>(sliding_stack(), "", {}), 200, 10);
    // The solver's default: only the rows above the stack are skipped.
    run_both<2, GimpShape>("sliding stack, default gap, " + t,
                           make_both<2, GimpShape>(sliding_stack(), "", {}, kMinSkippedNodes), 200,
                           10);
  }
  omp_set_num_threads(saved);
}

TEST(ActiveNodes, SlidingStackTravelsAcrossTiles) {
  // The scene does what the bitwise test needs: the stack moves several
  // tiles (4 cells = 2 mm) and the floor carries its weight.
  Runs r = make_both<2, GimpShape>(sliding_stack(), "", {});
  const auto x0 = r.skip->particle_field("position").values;
  for (int s = 0; s < 200; ++s) r.skip->step();
  const auto x1 = r.skip->particle_field("position").values;
  EXPECT_GT(x1[0] - x0[0], 6.0) << "the stack should slide over three tiles";
  const auto reactions = r.skip->reactions();
  ASSERT_EQ(reactions.size(), 1u);
  EXPECT_GT(reactions[0].force[1], 0.0) << "the floor should push the stack up";
}

TEST(ActiveNodes, ShippedScenesBitwise) {
  run_both<2, GimpShape>("collision, tiles of 4",
                         make_both<2, GimpShape>("", "collision.toml", {"grid.tile=4"}), 120, 20);
  run_both<2, GimpShape>("two-layer", make_both<2, GimpShape>("", "two_layer.toml", {}), 60, 20);
  run_both<2, GimpShape>("rigid incline", make_both<2, GimpShape>("", "incline_block.toml", {}), 60,
                         20);
  // Every other shipped 2D scene whose grid has nodes to skip
  // (shear_blocks and bar_vibration: their bodies' tiles and neighbours
  // cover the grid).
  for (const char* file :
       {"series_bars.toml", "dls.toml", "incline_disk.toml", "two_layer_mid.toml"})
    run_both<2, GimpShape>(file, make_both<2, GimpShape>("", file, {}), 40, 20);
  run_both<2, GimpShape>(
      "collision, USL",
      make_both<2, GimpShape>("", "collision.toml", {"grid.tile=4", "simulation.scheme=\"USL\""}),
      60, 20);
  // float: the same grid passes on the float columns.
  run_both<2, GimpShape, float>(
      "collision, float",
      make_both<2, GimpShape, float>("", "collision.toml",
                                     {"grid.tile=4", "simulation.precision=\"float\""}),
      60, 20);
}

TEST(ActiveNodes, SphereInCube3DBitwise) {
  run_both<3, GimpShape>("sphere in cube", make_both<3, GimpShape>("", "sphere_in_cube.toml", {}),
                         20, 10);
}

}  // namespace
