// drop_gradients_across_planes (kernels/support_gradients.hpp): at the
// multimaterial nodes of a symmetry plane each field's domain gradient loses
// the plane's normal component, unless the gradient lies mostly across the
// plane or the node lies on planes along every axis; on a mirror, wherever
// it points out through the plane.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "kernels/support_gradients.hpp"

namespace mmpm {
namespace {

constexpr unsigned char kX = 1, kY = 2;

struct Grid2 {
  static constexpr std::size_t kNodes = 4;
  std::vector<double> gx, gy;  // 2 fields x 4 nodes
  GridView<2, double> view;
  Grid2() : gx(2 * kNodes), gy(2 * kNodes) {
    view.nodes = kNodes;
    view.fields = 2;
    view.g = {gx.data(), gy.data()};
  }
  void set(int f, std::size_t node, double x, double y) {
    gx[view.at(f, node)] = x;
    gy[view.at(f, node)] = y;
  }
  std::array<double, 2> get(int f, std::size_t node) const {
    return {gx[view.at(f, node)], gy[view.at(f, node)]};
  }
};

TEST(SupportGradients, TheGradientAcrossAPlaneIsDroppedWhereItLeansAcrossIt) {
  Grid2 G;
  // node 0: on a plane normal to x; field 0 leans 45 degrees across it (a
  // body's corner on the plane), field 1 lies mostly in it.
  G.set(0, 0, -1.0, 1.0);
  G.set(1, 0, 0.25, -2.0);
  // node 1: on the same plane, field 0 mostly across it (a face lying on the
  // plane): |g_in_plane| = 0.4 < |g| / 2, left alone; field 1 exactly at
  // |g_in_plane| = |g| / 2 (3 * 1 = 3), dropped.
  G.set(0, 1, 2.0, 0.4);
  G.set(1, 1, 1.7320508075688772, 1.0);
  // node 2: on planes along x and y (a 2D corner): left alone.
  G.set(0, 2, 1.0, 1.0);
  // node 3: on the plane but not a multimaterial node: not visited.
  G.set(0, 3, 1.0, 1.0);
  const std::vector<unsigned char> axes = {kX, kX, kX | kY, kX};
  const std::vector<std::uint32_t> nodes = {0, 1, 2};
  drop_gradients_across_planes(G.view, nodes.data(), nodes.size(), axes.data());
  EXPECT_EQ(G.get(0, 0), (std::array<double, 2>{0.0, 1.0}));
  EXPECT_EQ(G.get(1, 0), (std::array<double, 2>{0.0, -2.0}));
  EXPECT_EQ(G.get(0, 1), (std::array<double, 2>{2.0, 0.4}));
  EXPECT_EQ(G.get(1, 1), (std::array<double, 2>{0.0, 1.0}));
  EXPECT_EQ(G.get(0, 2), (std::array<double, 2>{1.0, 1.0}));
  EXPECT_EQ(G.get(0, 3), (std::array<double, 2>{1.0, 1.0}));
}

// On a mirror (body on the +x side) a field's component across the plane
// goes whenever it points out through it (-x: the body's cut, which the
// image cancels), however large; one pointing into the body's side (a
// material past the plane with a face on it) stays. A corner of two mirrors
// loses both components that point out.
TEST(SupportGradients, OnAMirrorTheCutsGradientGoesWhateverItsSize) {
  Grid2 G;
  G.set(0, 0, -2.0, 0.4);  // mostly across, out through the plane: dropped
  G.set(1, 0, 2.0, 0.4);   // mostly across, into the body's side: kept
  G.set(0, 1, -1.0, 1.0);
  G.set(0, 2, -1.0, -1.0);  // corner of mirrors x (body +x) and y (body +y)
  G.set(1, 2, -1.0, 1.0);
  const std::vector<unsigned char> axes = {kX, kX, kX | kY, kX};
  // bit 2d: body on +d; bit 2d + 1: on -d.
  const std::vector<unsigned char> side = {1, 1, 1 | 4, 1};
  const std::vector<std::uint32_t> nodes = {0, 1, 2};
  drop_gradients_across_planes(G.view, nodes.data(), nodes.size(), axes.data(), side.data());
  EXPECT_EQ(G.get(0, 0), (std::array<double, 2>{0.0, 0.4}));
  EXPECT_EQ(G.get(1, 0), (std::array<double, 2>{2.0, 0.4}));
  EXPECT_EQ(G.get(0, 1), (std::array<double, 2>{0.0, 1.0}));
  EXPECT_EQ(G.get(0, 2), (std::array<double, 2>{0.0, 0.0}));
  EXPECT_EQ(G.get(1, 2), (std::array<double, 2>{0.0, 1.0}));
  // The body on the -x side: the cut's gradient points along +x.
  Grid2 H;
  H.set(0, 0, 2.0, 0.4);
  const std::vector<unsigned char> below = {2, 0, 0, 0};
  drop_gradients_across_planes(H.view, nodes.data(), 1, axes.data(), below.data());
  EXPECT_EQ(H.get(0, 0), (std::array<double, 2>{0.0, 0.4}));
}

TEST(SupportGradients, ANodeOffThePlanesAndAGridWithoutGradientsAreLeftAlone) {
  Grid2 G;
  G.set(0, 0, -1.0, 1.0);
  const std::vector<unsigned char> axes = {0, 0, 0, 0};
  const std::vector<std::uint32_t> nodes = {0};
  drop_gradients_across_planes(G.view, nodes.data(), nodes.size(), axes.data());
  EXPECT_EQ(G.get(0, 0), (std::array<double, 2>{-1.0, 1.0}));
  GridView<2, double> none;  // no gradient scattered (specified normals, paper area)
  none.nodes = 4;
  none.fields = 2;
  drop_gradients_across_planes(none, nodes.data(), nodes.size(), axes.data());
}

}  // namespace
}  // namespace mmpm
