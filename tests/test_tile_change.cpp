// G2P's tile-change test (kernels/binning.hpp PositionTile::any_moved): one
// vectorised loop over a range must answer what the particle-by-particle
// test answers, tile(position) != tile(key), for every range, wherever in
// the range (vector body or remainder) the one moved particle sits, with
// the tiles stored color by color (keys hold color-major slots) and in
// tile order.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "kernels/binning.hpp"

namespace {

template <int D, class Real>
struct TileChangeCase {
  mmpm::TileLayout<D> layout;
  std::array<Real, 3> origin{Real(-0.3), Real(0.7), Real(-1.1)};
  std::array<Real, 3> h{Real(0.1), Real(0.2), Real(0.15)};
  std::array<std::vector<Real>, D> x;
  std::vector<std::uint32_t> key;

  // n positions from two cells below the grid to two cells above it (the
  // keys clamp those into the edge cells), each keyed by its own cell.
  TileChangeCase(int tile_edge, bool color_major, std::size_t n, unsigned seed) {
    layout.setup(tile_edge, {37, 21, 13}, color_major);
    std::mt19937 rng(seed);
    for (int d = 0; d < D; ++d) {
      std::uniform_real_distribution<double> u(-2.0, layout.cells[std::size_t(d)] + 2.0);
      for (std::size_t p = 0; p < n; ++p)
        x[std::size_t(d)].push_back(origin[std::size_t(d)] + Real(u(rng)) * h[std::size_t(d)]);
    }
    // A few particles exactly on tile boundaries (the floor decides).
    for (std::size_t p = 0; p < n; p += 97)
      for (int d = 0; d < D; ++d)
        x[std::size_t(d)][p] = origin[std::size_t(d)] + Real(layout.T) * h[std::size_t(d)];
    for (std::size_t p = 0; p < n; ++p) key.push_back(key_of(p));
  }
  std::uint32_t key_of(std::size_t p) const {
    std::array<int, 3> c{0, 0, 0};
    for (int d = 0; d < D; ++d) {
      const auto k = std::size_t(d);
      c[k] = mmpm::cell_of(x[k][p], origin[k], Real(1) / h[k]);
    }
    return layout.key(c);
  }
  mmpm::PositionTile<D, Real> test() const {
    std::array<const Real*, D> pos;
    for (int d = 0; d < D; ++d) pos[std::size_t(d)] = x[std::size_t(d)].data();
    return mmpm::PositionTile<D, Real>::of(layout, origin, h, pos);
  }
  // The particle-by-particle answer for [b, e).
  bool reference(std::size_t b, std::size_t e) const {
    for (std::size_t p = b; p < e; ++p)
      if (layout.tile_of_key(key_of(p)) != layout.tile_of_key(key[p])) return true;
    return false;
  }
};

template <int D, class Real>
void check_tile_change(int tile_edge, bool color_major) {
  SCOPED_TRACE(testing::Message() << "D " << D << ", tile edge " << tile_edge
                                  << (color_major ? ", color-major" : ", tile order"));
  const std::size_t n = 203;  // not a multiple of any vector width
  TileChangeCase<D, Real> c(tile_edge, color_major, n, 11u + unsigned(tile_edge));
  const auto test = c.test();
  ASSERT_FALSE(c.reference(0, n));
  EXPECT_FALSE(test.any_moved(c.key.data(), 0, n));
  EXPECT_FALSE(test.any_moved(c.key.data(), 5, 5));  // empty range
  // One particle at a time keyed into another tile (same cell inside it),
  // then restored: only ranges holding it report a move.
  std::mt19937 rng(7);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t saved = c.key[i];
    const std::uint32_t local = saved & (c.layout.keys_per_tile - 1);
    const std::uint32_t slot = (c.layout.slot_of_key(saved) + 1) % c.layout.tile_count;
    c.key[i] = (slot << c.layout.key_shift) | local;
    std::uniform_int_distribution<std::size_t> below(0, i), above(i + 1, n);
    const std::size_t b = below(rng), e = above(rng);
    ASSERT_TRUE(c.reference(b, e));
    EXPECT_TRUE(test.any_moved(c.key.data(), b, e))
        << "particle " << i << " in [" << b << ", " << e << ")";
    EXPECT_TRUE(test.any_moved(c.key.data(), i, i + 1)) << "particle " << i;
    EXPECT_FALSE(test.any_moved(c.key.data(), 0, i)) << "particle " << i;
    EXPECT_FALSE(test.any_moved(c.key.data(), i + 1, n)) << "particle " << i;
    c.key[i] = saved;
  }
}

TEST(TileChange, AnyMovedAgreesWithTheParticleByParticleTest2D) {
  for (int t : {4, 8, 16})
    for (bool color_major : {true, false}) {
      check_tile_change<2, double>(t, color_major);
      check_tile_change<2, float>(t, color_major);
    }
}

TEST(TileChange, AnyMovedAgreesWithTheParticleByParticleTest3D) {
  for (int t : {4, 8})
    for (bool color_major : {true, false}) {
      check_tile_change<3, double>(t, color_major);
      check_tile_change<3, float>(t, color_major);
    }
}

}  // namespace
