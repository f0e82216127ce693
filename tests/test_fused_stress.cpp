// The constitutive update fused into the G2P gradient pass ([simulation]
// fuse_constitutive = true, not the default; kernels/g2p.hpp kStressUpdate)
// computes what the
// separate constitutive pass computes. Fusing applies only when every
// stressed material is isotropic (kernels/constitutive.hpp
// IsotropicStressUpdate); other scenes fall back to the separate pass.
//
// Scenes: 2D plane strain, three bodies side by side in one velocity
// field, 60 x 20 cells of 1 mm, 2 x 2 particles per cell (3 x 800
// particles), a non-uniform initial velocity so every particle strains; 40
// steps of each scheme (USL, USF, MUSL) and shape (gimp, linear). The fused
// scene has three isotropic materials of different E and nu (so the
// per-material table lookup is exercised); the fallback scene swaps two of
// them for transversely isotropic and neo-Hookean materials. The two paths
// evaluate the same expressions; only the compiler's multiply-add
// contraction may differ between the inlined and the separate update.
// Tolerances: positions, velocities, volumes 1e-12 relative to the field's
// largest magnitude; stress 1e-13 E_max absolute; strain 1e-13 absolute
// (the strains here are 1e-4 .. 1e-3, so this is ~1e-10 relative or better).
// Failure: a particle whose volume inverts stops the run in stage
// "constitutive" with the same message fused and unfused.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

using namespace mmpm;

constexpr double kEmax = 4000.0;  // MPa, the stiffest modulus of either scene

// Materials 1 and 2: isotropic (fusable) or transverse and neo-Hookean.
std::string three_materials(const std::string& scheme, const std::string& shape, bool fuse,
                            bool all_isotropic = true) {
  const std::string m1 = all_isotropic ? "[[material]]\nname = \"wood\"\ntype = \"isotropic\"\n"
                                         "density = 5.0e-4\nE = 4000.0\nnu = 0.2\n\n"
                                       : "[[material]]\nname = \"wood\"\ntype = \"transverse\"\n"
                                         "density = 5.0e-4\nEA = 4000.0\nET = 800.0\nGA = 300.0\n"
                                         "nuA = 0.2\nnuT = 0.3\naxis = [1.0, 1.0]\n\n";
  const std::string m2 = std::string("[[material]]\nname = \"rubber\"\ntype = \"") +
                         (all_isotropic ? "isotropic" : "neohookean") +
                         "\"\ndensity = 1.0e-3\nE = 500.0\nnu = 0.45\n\n";
  return "[simulation]\ndimension = 2\nplane = \"strain\"\nend_time = 1.0\ncfl = 0.4\n"
         "scheme = \"" +
         scheme + "\"\nfuse_constitutive = " + (fuse ? "true" : "false") +
         "\n\n[grid]\norigin = [0.0, 0.0]\ncell = [1.0, 1.0]\ncells = [68, 28]\nshape = \"" +
         shape +
         "\"\n\n"
         "[[material]]\nname = \"iso\"\ntype = \"isotropic\"\ndensity = 1.0e-3\nE = 1000.0\nnu = "
         "0.3\n\n" +
         m1 + m2 +
         "[[body]]\nname = \"b0\"\nmaterial = \"iso\"\nshape = \"box\"\nmin = [4.0, 4.0]\n"
         "max = [24.0, 24.0]\nparticles_per_cell = 2\n\n"
         "[[body]]\nname = \"b1\"\nmaterial = \"wood\"\nshape = \"box\"\nmin = [24.0, 4.0]\n"
         "max = [44.0, 24.0]\nparticles_per_cell = 2\n\n"
         "[[body]]\nname = \"b2\"\nmaterial = \"rubber\"\nshape = \"box\"\nmin = [44.0, 4.0]\n"
         "max = [64.0, 24.0]\nparticles_per_cell = 2\n";
}

std::unique_ptr<Simulation> start(const std::string& text) {
  std::unique_ptr<Simulation> sim = make_simulation(parse_scene_text(text, "fused.toml"));
  const std::vector<double> x = sim->particle_field("position").values;
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < x.size() / 2; ++p) {
    v[2 * p] = 3.0 * std::sin(x[2 * p + 1] / 4.0) + 0.05 * (x[2 * p] - 34.0);
    v[2 * p + 1] = 2.0 * std::cos(x[2 * p] / 5.0);
  }
  sim->set_particle_field("velocity", v);
  return sim;
}

// last_fraction < 1: the 40th step is that fraction of a step (step_within,
// as a run's last step ending between two multiples of dt).
void expect_same_run(const std::string& scheme, const std::string& shape,
                     double last_fraction = 1.0) {
  auto fused = start(three_materials(scheme, shape, true));
  auto separate = start(three_materials(scheme, shape, false));
  for (int s = 0; s < 39; ++s) fused->step(), separate->step();
  if (last_fraction < 1) {
    const double t_end = fused->time() + last_fraction * fused->dt();
    fused->step_within(t_end), separate->step_within(t_end);
    ASSERT_EQ(fused->time(), t_end);
  } else {
    fused->step(), separate->step();
  }
  // The separate run timed a constitutive stage; the fused one did not
  // (so the fused path really ran).
  EXPECT_GT(separate->stage_calls()[kStageConstitutive], 0);
  EXPECT_EQ(fused->stage_calls()[kStageConstitutive], 0);
  for (const char* name : {"position", "velocity", "stress", "volume", "strain"}) {
    const auto a = fused->particle_field(name).values;
    const auto b = separate->particle_field(name).values;
    ASSERT_EQ(a.size(), b.size());
    double scale = 0, diff = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      scale = std::max(scale, std::abs(b[i]));
      diff = std::max(diff, std::abs(a[i] - b[i]));
    }
    EXPECT_GT(scale, 0.0) << name;
    const std::string n = name;
    const double tolerance =
        n == "stress" ? 1e-13 * kEmax : (n == "strain" ? 1e-13 : 1e-12 * scale);
    EXPECT_LE(diff, tolerance) << scheme << " " << shape << " " << name;
  }
  // Stress really built up in all three materials (the test is not vacuous).
  const auto stress = fused->particle_field("stress").values;
  const auto material = fused->particle_field("material").values;
  double peak[3] = {0, 0, 0};
  for (std::size_t p = 0; p < material.size(); ++p)
    for (int c = 0; c < 4; ++c)
      peak[int(material[p])] = std::max(peak[int(material[p])], std::abs(stress[4 * p + c]));
  for (int m = 0; m < 3; ++m) EXPECT_GT(peak[m], 1e-3) << "material " << m;
}

TEST(FusedConstitutive, MatchesSeparatePassMUSL) {
  expect_same_run("MUSL", "gimp");
}
TEST(FusedConstitutive, MatchesSeparatePassUSL) {
  expect_same_run("USL", "gimp");
}
TEST(FusedConstitutive, MatchesSeparatePassUSF) {
  expect_same_run("USF", "gimp");
}
TEST(FusedConstitutive, MatchesSeparatePassLinearMUSL) {
  expect_same_run("MUSL", "linear");
}
// The fused update takes the shortened last step's dt, not the run's: with
// the run's, a two-layer scene ending 0.2 of a step past a multiple of dt
// read 0.33 % off in stress.
TEST(FusedConstitutive, MatchesSeparatePassInAShortLastStep) {
  for (const char* scheme : {"USL", "MUSL"}) expect_same_run(scheme, "gimp", 0.3);
}

// A transversely isotropic or neo-Hookean material turns fusing off even
// when the scene asks for it: the run takes the separate pass and is
// bitwise the run that asked for no fusing.
TEST(FusedConstitutive, OtherMaterialTypesFallBackToSeparatePass) {
  auto asked = start(three_materials("MUSL", "gimp", true, false));
  auto separate = start(three_materials("MUSL", "gimp", false, false));
  for (int s = 0; s < 10; ++s) asked->step(), separate->step();
  EXPECT_EQ(asked->stage_calls()[kStageConstitutive], 10);
  for (const char* name : {"position", "velocity", "stress", "volume"})
    EXPECT_EQ(asked->particle_field(name).values, separate->particle_field(name).values) << name;
}

// v = (-k x, k y) with dt k = 2: det(I + dt L) = (1 - 2)(1 + 2) < 0 in the
// first step, a finite velocity field (G2P succeeds) and an inverted volume.
std::string inverting(bool fuse, const std::string& type) {
  return "[simulation]\ndimension = 2\nend_time = 1.0\ndt = 0.01\nforce = true\n"
         "fuse_constitutive = " +
         std::string(fuse ? "true" : "false") +
         "\n\n[grid]\norigin = [-8.0, -8.0]\ncell = [1.0, 1.0]\ncells = [16, 16]\n"
         "shape = \"linear\"\n\n"
         "[[material]]\nname = \"rubber\"\ntype = \"" +
         type +
         "\"\ndensity = 1.0e-3\nE = 1.0\nnu = 0.3\n\n"
         "[[body]]\nname = \"b\"\nmaterial = \"rubber\"\nshape = \"box\"\nmin = [-4.0, -4.0]\n"
         "max = [4.0, 4.0]\nparticles_per_cell = 2\n";
}

std::string failure_of(bool fuse, const std::string& type) {
  std::unique_ptr<Simulation> sim =
      make_simulation(parse_scene_text(inverting(fuse, type), "inv.toml"));
  const std::vector<double> x = sim->particle_field("position").values;
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < x.size() / 2; ++p)
    v[2 * p] = -200.0 * x[2 * p], v[2 * p + 1] = 200.0 * x[2 * p + 1];
  sim->set_particle_field("velocity", v);
  try {
    sim->step();
  } catch (const SimulationError& e) {
    return e.what();
  }
  return "no failure";
}

// Isotropic: the fused path's check; neo-Hookean: the separate pass's.
TEST(FusedConstitutive, InvertedParticleStopsInConstitutiveStage) {
  for (const char* type : {"isotropic", "neohookean"}) {
    const std::string fused = failure_of(true, type), separate = failure_of(false, type);
    EXPECT_NE(fused.find("stage constitutive, step 0, particle"), std::string::npos) << fused;
    EXPECT_NE(fused.find("J <= 0"), std::string::npos) << fused;
    EXPECT_EQ(fused, separate) << type;
  }
}

}  // namespace
