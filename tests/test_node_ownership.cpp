// Which thread works on which grid nodes (kernels/node_ownership.hpp): the
// split follows the particles' tiles (balanced inside the band the threads
// share), and the node loops that use it (with the supports they apply)
// give the same results whatever the split and the thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/node_ownership.hpp"
#include "kernels/supports.hpp"

namespace {

using mmpm::NodeOwnership;

// The tile schedule of one particle per cell in cells [lo, hi) of each
// direction, sorted.
template <int D>
mmpm::TileSchedule block_schedule(const mmpm::TileLayout<D>& layout, std::array<int, 3> lo,
                                  std::array<int, 3> hi) {
  std::vector<std::uint32_t> keys;
  for (int k = D == 3 ? lo[2] : 0; k < (D == 3 ? hi[2] : 1); ++k)
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int i = lo[0]; i < hi[0]; ++i) keys.push_back(layout.key({i, j, k}));
  std::sort(keys.begin(), keys.end());
  mmpm::TileSchedule schedule;
  schedule.build(layout, keys.data(), keys.size());
  return schedule;
}

// The cuts below come out the same with particles stored color by color
// and in tile order: in both, each color's tiles are split in tile order.
TEST(NodeOwnership, CutsNearestTheEvenSplitInsideTheThreadsBands2D) {
  for (const bool color_major : {true, false}) {
    SCOPED_TRACE(color_major ? "color-major" : "tile order");
    // 64 x 64 cells (65 x 65 = 4225 nodes), tiles of 8: an 8 x 8 tile grid,
    // one particle per cell in every cell. Thread 1's tiles begin in tile
    // row 4 (colors on even rows) and 5 (odd rows): bands node rows 32 ..
    // 48. The even cut (node 2112, row 32.5) lies inside.
    mmpm::TileLayout<2> layout;
    layout.setup(8, {64, 64, 1}, color_major);
    const std::array<int, 3> nodes{65, 65, 1};
    const auto all = block_schedule<2>(layout, {0, 0, 0}, {64, 64, 1});
    const NodeOwnership two = mmpm::node_ownership<2>(layout, nodes, all, 2);
    EXPECT_EQ(two.split, (std::vector<std::size_t>{0, 2112, 65 * 65}));
    // Four threads: tile rows 2-3, 4-5, 6-7 (bands from rows 16, 32, 48)
    // hold the even cuts 1056, 2112, 3168.
    const NodeOwnership four = mmpm::node_ownership<2>(layout, nodes, all, 4);
    EXPECT_EQ(four.split, (std::vector<std::size_t>{0, 1056, 2112, 3168, 65 * 65}));
    // Particles only in the upper-right quarter (cells 32..63): thread 1's
    // tiles begin in tile rows 6 and 7 (bands rows 48 .. 64); the even cut
    // lies below, so the cut is the bands' first node.
    const auto quarter = block_schedule<2>(layout, {32, 32, 0}, {64, 64, 1});
    const NodeOwnership q = mmpm::node_ownership<2>(layout, nodes, quarter, 2);
    EXPECT_EQ(q.split, (std::vector<std::size_t>{0, 48 * 65, 65 * 65}));
    // Particles only in cells x 0..31, y 0..15: thread 1's tiles begin in
    // tile rows 0 and 1 (bands rows 0 .. 16); the even cut lies above, so
    // the cut is the bands' end and no node row that only thread 0 wrote
    // goes to thread 1.
    const auto low = block_schedule<2>(layout, {0, 0, 0}, {32, 16, 1});
    const NodeOwnership l = mmpm::node_ownership<2>(layout, nodes, low, 2);
    EXPECT_EQ(l.split, (std::vector<std::size_t>{0, 16 * 65, 65 * 65}));
  }
}

TEST(NodeOwnership, CutsNearestTheEvenSplitInsideTheThreadsBands3D) {
  for (const bool color_major : {true, false}) {
    SCOPED_TRACE(color_major ? "color-major" : "tile order");
    // 16^3 cells (17^3 = 4913 nodes), tiles of 4: thread 1's tiles begin in
    // tile layers z = 2 and 3 (bands: node layers 8 .. 16), which hold the
    // even cut 2456, rounded to the nearest multiple of 16 nodes (a
    // cache line of floats): 2464.
    mmpm::TileLayout<3> layout;
    layout.setup(4, {16, 16, 16}, color_major);
    const std::array<int, 3> nodes{17, 17, 17};
    const auto all = block_schedule<3>(layout, {0, 0, 0}, {16, 16, 16});
    const NodeOwnership two = mmpm::node_ownership<3>(layout, nodes, all, 2);
    EXPECT_EQ(two.split, (std::vector<std::size_t>{0, 2464, 17 * 17 * 17}));
    EXPECT_EQ(two.split[1] % mmpm::kNodeCutAlign, 0u);
  }
}

TEST(NodeOwnership, ThickTileLayersNoLongerLeaveOneThreadAThirdOfTheNodes) {
  for (const bool color_major : {true, false}) {
    SCOPED_TRACE(color_major ? "color-major" : "tile order");
    // The 3d_gimp_1mat bench geometry: 28 x 28 x 26 cells (29 x 29 x 27 =
    // 22 707 nodes), tiles of 8, particles in cells 2..25 x 2..25 x 2..23.
    // Thread 1's tiles begin in tile layers z = 1 or 2 (node layers 8 ..
    // 24). A cut at the first node of layer 8 gave thread 0 ~30 % of the
    // nodes. The cut is the even one (11 353) on the nearest multiple of
    // 16 nodes, inside those bands.
    mmpm::TileLayout<3> layout;
    layout.setup(8, {28, 28, 26}, color_major);
    const std::array<int, 3> nodes{29, 29, 27};
    const auto block = block_schedule<3>(layout, {2, 2, 2}, {26, 26, 24});
    const NodeOwnership two = mmpm::node_ownership<3>(layout, nodes, block, 2);
    const std::size_t total = 29 * 29 * 27, layer = 29 * 29;
    EXPECT_EQ(two.split, (std::vector<std::size_t>{0, 11360, total}));
    EXPECT_GE(two.split[1], 8 * layer);
    EXPECT_LE(two.split[1], 24 * layer);
  }
}

TEST(NodeOwnership, OtherTeamSizesAndNoParticlesGetAnEvenSplit) {
  NodeOwnership own;
  own.split = {0, 10, 100};
  EXPECT_EQ(own.range(100, 2, 0), (std::pair<std::size_t, std::size_t>{0, 10}));
  EXPECT_EQ(own.range(100, 2, 1), (std::pair<std::size_t, std::size_t>{10, 100}));
  // A one-thread team (a loop below its parallel threshold) does every node.
  EXPECT_EQ(own.range(100, 1, 0), (std::pair<std::size_t, std::size_t>{0, 100}));
  EXPECT_EQ(own.range(100, 3, 1), (std::pair<std::size_t, std::size_t>{33, 66}));
  // A split made for another grid size is not used.
  EXPECT_EQ(own.range(50, 2, 1), (std::pair<std::size_t, std::size_t>{25, 50}));
  // Reduction chunks go to the thread owning their first node.
  EXPECT_EQ(own.chunks(100, 16, 2, 0), (std::pair<std::size_t, std::size_t>{0, 1}));
  EXPECT_EQ(own.chunks(100, 16, 2, 1), (std::pair<std::size_t, std::size_t>{1, 7}));
  mmpm::TileLayout<2> layout;
  layout.setup(8, {16, 16, 1});
  EXPECT_TRUE(mmpm::node_ownership<2>(layout, {17, 17, 1}, mmpm::TileSchedule{}, 2).split.empty());
}

// A grid of 2 fields with random masses (some slivers, some empty), momenta
// and forces, as the momentum update finds it after P2G.
struct UpdateGrid {
  static constexpr int D = 2;
  std::size_t nodes;
  std::vector<double> m, p0, p1, f0, f1, fi0, fi1, v0, v1, dv0, dv1;
  mmpm::GridView<2, double> G;
  mmpm::GridVelocity<2, double> V;
  explicit UpdateGrid(std::array<int, 3> dims)
      : nodes(std::size_t(dims[0]) * std::size_t(dims[1])) {
    const std::size_t total = 2 * nodes;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    for (auto* a : {&m, &p0, &p1, &f0, &f1, &fi0, &fi1, &v0, &v1, &dv0, &dv1}) a->assign(total, 0);
    for (std::size_t i = 0; i < total; ++i) {
      const double r = u(rng);
      m[i] = r < -0.5 ? 0.0 : (r < -0.4 ? 1e-14 : 1 + r);
      p0[i] = u(rng), p1[i] = u(rng), f0[i] = u(rng), f1[i] = u(rng);
      fi0[i] = u(rng), fi1[i] = u(rng);
    }
    G.nodes_per_dim = dims;
    G.nodes = nodes;
    G.fields = 2;
    G.m = m.data();
    G.p = {p0.data(), p1.data()};
    G.f = {f0.data(), f1.data()};
    G.fi = {fi0.data(), fi1.data()};
    V.vel = {v0.data(), v1.data()};
    V.dvel = {dv0.data(), dv1.data()};
  }
};

// p, vel and dvel of both grids bit for bit.
void expect_same_momenta_and_velocities(const UpdateGrid& ref, const UpdateGrid& g,
                                        const std::string& where) {
  for (auto [a, b] : {std::pair{&ref.p0, &g.p0},
                      {&ref.p1, &g.p1},
                      {&ref.v0, &g.v0},
                      {&ref.v1, &g.v1},
                      {&ref.dv0, &g.dv0},
                      {&ref.dv1, &g.dv1}})
    EXPECT_EQ(std::memcmp(a->data(), b->data(), a->size() * sizeof(double)), 0) << where;
}

TEST(NodeOwnership, GridUpdateAndVelocitiesBitwiseWhateverTheSplit) {
  // 300 x 170 nodes (13 reduction chunks per field); 1 thread vs 2 threads
  // with several cuts. Damping on: the loss is a real sum, computed in the
  // reduction's fixed chunks. Damping off: each thread updates exactly its
  // own nodes (no chunks), with the velocities in a separate pass or in the
  // update's own (GridUpdateParams::velocities).
  const std::array<int, 3> dims{300, 170, 1};
  for (const double damping : {0.7, 0.0})
    for (const bool fused : {false, true}) {
      mmpm::GridUpdateParams q;
      q.dt = 1e-3;
      q.damping = damping;
      q.mass_threshold = 1e-12;
      q.body_accel[1] = -9.81;
      q.has_interface_force = true;
      q.velocities = fused;
      auto run = [&](int threads, std::vector<std::size_t> split, UpdateGrid& g) {
        const int saved = omp_get_max_threads();
        omp_set_num_threads(threads);
        NodeOwnership own;
        own.split = std::move(split);
        const double loss = mmpm::grid_update(g.G, g.V, q, own);
        if (!fused) mmpm::grid_velocities(g.G, g.V, 1e-12, own);
        omp_set_num_threads(saved);
        return loss;
      };
      UpdateGrid ref(dims);
      const double loss_ref = run(1, {}, ref);
      if (damping > 0) {
        EXPECT_GT(loss_ref, 0.0);
      }
      const std::size_t n = ref.nodes;
      for (const auto& split : std::vector<std::vector<std::size_t>>{
               {}, {0, 1, n}, {0, 4096 * 5 + 17, n}, {0, n, n}, {0, 0, n}, {0, 3, n}}) {
        UpdateGrid g(dims);
        const double loss = run(2, split, g);
        const std::string where = "damping " + std::to_string(damping) +
                                  (fused ? ", fused velocities" : "") + ", split at " +
                                  std::to_string(split.empty() ? 0 : split[1]);
        EXPECT_EQ(loss, loss_ref) << where;
        expect_same_momenta_and_velocities(ref, g, where);
      }
    }
}

TEST(NodeOwnership, MomentumVelocitiesBitwiseWhateverTheSplit) {
  // vel = p/m alone (MUSL's second transfer): a vectorised loop whose
  // remainder moves with the split, so every cut must give the same bits.
  const std::array<int, 3> dims{300, 170, 1};
  auto run = [&](int threads, std::vector<std::size_t> split, UpdateGrid& g) {
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    NodeOwnership own;
    own.split = std::move(split);
    mmpm::grid_momentum_velocities(g.G, g.V, 1e-12, own);
    omp_set_num_threads(saved);
  };
  UpdateGrid ref(dims);
  run(1, {}, ref);
  const std::size_t n = ref.nodes;
  for (const auto& split : std::vector<std::vector<std::size_t>>{
           {}, {0, 1, n}, {0, 4096 * 5 + 17, n}, {0, n, n}, {0, 0, n}, {0, 3, n}}) {
    UpdateGrid g(dims);
    run(2, split, g);
    for (auto [a, b] : {std::pair{&ref.v0, &g.v0}, {&ref.v1, &g.v1}})
      EXPECT_EQ(std::memcmp(a->data(), b->data(), a->size() * sizeof(double)), 0)
          << "split at " << (split.empty() ? 0 : split[1]);
  }
}

// The supports as the Stepper applied them before they moved into the node
// passes: one serial loop after the pass, the reaction summed as it went.
std::array<double, 3> serial_supports(UpdateGrid& g, const mmpm::SupportView<double>& bc,
                                      const unsigned char* rigid, double thr, double dt,
                                      bool with_dvel) {
  std::array<double, 3> reaction{0, 0, 0};
  for (int f = 0; f < g.G.fields; ++f) {
    if (rigid[f]) continue;
    for (std::size_t k = 0; k < bc.count; ++k) {
      const std::size_t i = std::size_t(f) * g.nodes + bc.nodes[k];
      const double m = g.G.m[i];
      if (!(m > thr)) {
        if (with_dvel)
          for (int d = 0; d < 2; ++d)
            if (bc.fix[d]) g.V.dvel[d][i] = 0;
        continue;
      }
      for (int d = 0; d < 2; ++d) {
        if (!bc.fix[d]) continue;
        const double change = bc.velocity[d] - g.V.vel[d][i];
        reaction[std::size_t(d)] += m * change / dt;
        g.V.vel[d][i] = bc.velocity[d];
        if (with_dvel) g.V.dvel[d][i] += change;
        g.G.p[d][i] = m * bc.velocity[d];
      }
    }
  }
  return reaction;
}

TEST(NodeOwnership, SupportsAppliedByTheOwnersMatchTheSerialLoopBitwise) {
  // Two supports sharing a corner node on 300 x 170 nodes (slivers and
  // empty nodes among them): the left column fixed in x and y, the bottom
  // row in y, moving. Field 1 rigid in the second round (supports skip it).
  // Each node pass with the supports as its hook, on 2 threads with
  // several cuts, against the pass on 1 thread followed by the serial loop.
  const std::array<int, 3> dims{300, 170, 1};
  std::vector<std::uint32_t> left, bottom;
  for (std::uint32_t j = 0; j < 170; ++j) left.push_back(j * 300);
  for (std::uint32_t i = 0; i < 300; ++i) bottom.push_back(i);
  const double thr = 1e-12, dt = 1e-3;
  mmpm::GridUpdateParams q;
  q.dt = dt;
  q.mass_threshold = thr;
  q.body_accel[1] = -9.81;
  q.velocities = true;
  for (const unsigned char rigid1 : {0, 1}) {
    const unsigned char rigid[2] = {0, rigid1};
    std::vector<double> terms_left(2 * left.size() * 2, -1.0), terms_bottom(2 * bottom.size() * 2);
    std::array<mmpm::SupportView<double>, 2> views{};
    views[0].nodes = left.data(), views[0].count = left.size();
    views[0].fix[0] = views[0].fix[1] = true;
    views[0].velocity[0] = 0.25, views[0].velocity[1] = -0.5;
    views[0].reaction_terms = terms_left.data();
    views[1].nodes = bottom.data(), views[1].count = bottom.size();
    views[1].fix[1] = true;
    views[1].velocity[1] = 0.125;
    views[1].reaction_terms = terms_bottom.data();
    // The three passes that apply supports: the update with velocities
    // (with dvel), grid_velocities (with dvel), grid_momentum_velocities.
    for (int pass = 0; pass < 3; ++pass) {
      const bool with_dvel = pass < 2;
      UpdateGrid ref(dims);
      if (pass == 0) {
        mmpm::grid_update(ref.G, ref.V, q, {});
      } else if (pass == 1) {
        mmpm::GridUpdateParams q2 = q;
        q2.velocities = false;
        mmpm::grid_update(ref.G, ref.V, q2, {});
        mmpm::grid_velocities(ref.G, ref.V, thr, {});
      } else {
        mmpm::grid_momentum_velocities(ref.G, ref.V, thr, {});
      }
      std::array<std::array<double, 3>, 2> want{};
      for (int s = 0; s < 2; ++s)
        want[s] = serial_supports(ref, views[s], rigid, thr, dt, with_dvel);
      const std::size_t n = ref.nodes;
      for (const auto& split : std::vector<std::vector<std::size_t>>{
               {}, {0, 1, n}, {0, 4096 * 5 + 17, n}, {0, 150 * 300 + 1, n}, {0, n, n}}) {
        UpdateGrid g(dims);
        const int saved = omp_get_max_threads();
        omp_set_num_threads(2);
        NodeOwnership own;
        own.split = split;
        mmpm::Supports<double> S;
        S.list = views.data(), S.count = 2, S.rigid = rigid;
        S.mass_threshold = thr, S.dt = dt, S.with_dvel = with_dvel;
        auto hook = [&](int f, std::size_t b, std::size_t e) {
          mmpm::apply_supports(g.G, g.V, S, f, b, e);
        };
        if (pass == 0) {
          mmpm::grid_update(g.G, g.V, q, own, hook);
        } else if (pass == 1) {
          mmpm::GridUpdateParams q2 = q;
          q2.velocities = false;
          mmpm::grid_update(g.G, g.V, q2, own);
          mmpm::grid_velocities(g.G, g.V, thr, own, hook);
        } else {
          mmpm::grid_momentum_velocities(g.G, g.V, thr, own, hook);
        }
        omp_set_num_threads(saved);
        const std::string where = "pass " + std::to_string(pass) + ", rigid field 1 " +
                                  std::to_string(int(rigid1)) + ", split at " +
                                  std::to_string(split.empty() ? 0 : split[1]);
        expect_same_momenta_and_velocities(ref, g, where);
        if (!with_dvel) continue;
        for (int s = 0; s < 2; ++s) {
          const auto got = mmpm::sum_support_reaction<2>(views[s], 2, rigid);
          for (int d = 0; d < 3; ++d)
            EXPECT_EQ(got[std::size_t(d)], want[s][std::size_t(d)]) << where << ", support " << s;
        }
        // The supports did act: the fixed velocities are the support's.
        EXPECT_EQ(g.v0[left[5]], g.m[left[5]] > thr ? 0.25 : 0.0) << where;
      }
      if (with_dvel) {
        EXPECT_NE(want[0][0], 0.0);
      }
    }
  }
}

TEST(NodeOwnership, ZeroOwnedClearsEveryFieldOfEveryNode) {
  const std::size_t nodes = 20000;
  std::vector<double> a(3 * nodes, 1.0), b(3 * nodes, 2.0);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  NodeOwnership own;
  own.split = {0, 12345, nodes};
  mmpm::zero_owned(own, nodes, 3, std::array<double*, 3>{a.data(), nullptr, b.data()});
  omp_set_num_threads(saved);
  EXPECT_TRUE(std::all_of(a.begin(), a.end(), [](double x) { return x == 0.0; }));
  EXPECT_TRUE(std::all_of(b.begin(), b.end(), [](double x) { return x == 0.0; }));
}

}  // namespace
