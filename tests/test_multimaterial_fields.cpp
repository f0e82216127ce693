// The multimaterial fields (mx, Omega, g) scattered apart, from the tiles
// that reach a multimaterial node, or with the first P2G ([simulation]
// mm_fields_share, kernels/p2g_multimaterial.hpp) give bitwise the same
// run: the values at multimaterial nodes are the same sums in the same
// order, and nothing else reads them.
//
// Scene: 2D plane strain, uGIMP, 56 x 56 cells of 1 mm, a 48 x 48 mm
// polymer block holding 16 glass disks of radius 3.5 mm on an 11 mm pitch
// (nearly every tile reaches an interface), 2 x 2 particles per cell, an
// initial shear velocity field, 40 steps. Interactions: an imperfect
// interface with the mvg normal (the fields include g) under MUSL, and
// Coulomb contact with displacement separation under USF (the first P2G
// without the force). mm_fields_share = 1 scatters apart in every step,
// 0 with the first P2G from step 2 on; the counters say which ran.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

using namespace mmpm;

std::string inclusions(const std::string& scheme, const std::string& interaction, double share) {
  std::string s =
      "[simulation]\ndimension = 2\nplane = \"strain\"\nend_time = 1.0\ncfl = 0.4\n"
      "scheme = \"" +
      scheme + "\"\nmm_fields_share = " + std::to_string(share) +
      "\n\n[grid]\norigin = [0.0, 0.0]\ncell = [1.0, 1.0]\ncells = [56, 56]\n"
      "shape = \"gimp\"\n\n"
      "[[material]]\nname = \"polymer\"\ntype = \"isotropic\"\ndensity = 1.2e-3\n"
      "E = 2400.0\nnu = 0.33\n\n"
      "[[material]]\nname = \"glass\"\ntype = \"isotropic\"\ndensity = 2.5e-3\n"
      "E = 70000.0\nnu = 0.22\n\n"
      "[[body]]\nname = \"block\"\nmaterial = \"polymer\"\nshape = \"box\"\n"
      "min = [4.0, 4.0]\nmax = [52.0, 52.0]\nparticles_per_cell = 2\n";
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      s += "\n[[body]]\nname = \"disk" + std::to_string(4 * i + j) +
           "\"\nmaterial = \"glass\"\nshape = \"disk\"\ncenter = [" +
           std::to_string(11.5 + 11.0 * i) + ", " + std::to_string(11.5 + 11.0 * j) +
           "]\nradius = 3.5\nparticles_per_cell = 2\n";
  return s + "\n[[interaction]]\nmaterials = [\"glass\", \"polymer\"]\n" + interaction;
}

std::unique_ptr<Simulation> start(const std::string& text) {
  std::unique_ptr<Simulation> sim = make_simulation(parse_scene_text(text, "fields.toml"));
  const std::vector<double> x = sim->particle_field("position").values;
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < x.size() / 2; ++p) {
    v[2 * p] = 2.0 * std::sin(x[2 * p + 1] / 6.0);
    v[2 * p + 1] = 1.5 * std::cos(x[2 * p] / 7.0);
  }
  sim->set_particle_field("velocity", v);
  return sim;
}

void expect_same_run(const std::string& scheme, const std::string& interaction) {
  auto apart = start(inclusions(scheme, interaction, 1.0));
  auto with_p2g = start(inclusions(scheme, interaction, 0.0));
  long steps_with_p2g = 0, steps_apart = 0, mm_nodes = 0;
  for (int s = 0; s < 40; ++s) {
    apart->step(), with_p2g->step();
    steps_apart += !apart->counters().mm_fields_with_p2g;
    steps_with_p2g += with_p2g->counters().mm_fields_with_p2g;
    mm_nodes = apart->counters().multimaterial_nodes;
    ASSERT_EQ(mm_nodes, with_p2g->counters().multimaterial_nodes) << "step " << s;
  }
  EXPECT_EQ(steps_apart, 40) << "share 1: the fields are always scattered apart";
  EXPECT_EQ(steps_with_p2g, 39) << "share 0: with the first P2G from the second step on";
  EXPECT_GT(mm_nodes, 200) << "the disks' interfaces make many multimaterial nodes";
  for (const char* name : {"position", "velocity", "stress", "volume"}) {
    const auto a = apart->particle_field(name).values;
    const auto b = with_p2g->particle_field(name).values;
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0) << name;
  }
  const Energies ea = apart->energies(), eb = with_p2g->energies();
  EXPECT_EQ(ea.interface, eb.interface);
  EXPECT_EQ(ea.strain, eb.strain);
  EXPECT_GT(ea.strain, 0.0);
}

TEST(MultimaterialFields, ApartOrWithFirstP2GSameRunInterfaceMvgMUSL) {
  expect_same_run("MUSL", "law = \"interface\"\nDn = 1.0e4\nDt = 1.0e4\nnormal = \"mvg\"\n");
}
TEST(MultimaterialFields, ApartOrWithFirstP2GSameRunCoulombUSF) {
  expect_same_run("USF", "law = \"friction\"\nfriction = 0.3\nseparation = \"displacement\"\n");
}

}  // namespace
