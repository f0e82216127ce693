// Material models prepared once from the scene: kernel constants, the
// compliance used for the strain energy, and the wave speed for the time step.
#pragma once

#include <array>
#include <string>

#include "kernels/constitutive.hpp"
#include "scene/scene.hpp"

namespace mmpm {

struct MaterialModel {
  std::string name;
  MaterialType type = MaterialType::isotropic;
  double density = 1;
  ElasticKernelConstants k;
  double compliance[6][6] = {};  // Voigt, engineering shear (strain energy of small-strain types)
  double wave_speed = 0;         // largest dilatational speed, for the CFL time step
  bool rigid() const { return type == MaterialType::rigid; }
  bool finite_strain() const { return type == MaterialType::neohookean; }
};

// dimension and plane come from the scene's [simulation]; throws InputError
// for combinations the kernels do not model (neo-Hookean in plane stress).
MaterialModel make_material(const MaterialSpec& spec, int dimension, Plane plane);

// Velocity of a rigid material at time t (piecewise linear, held at the ends).
Vec3 rigid_velocity(const MaterialSpec& spec, double t);

// Its displacement from time 0 to t (the integral of rigid_velocity).
Vec3 rigid_displacement(const MaterialSpec& spec, double t);

}  // namespace mmpm
