#include "model/material.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "scene/error.hpp"

namespace mmpm {
namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;

// Voigt index of a tensor index pair (xx yy zz yz xz xy).
int voigt(int i, int j) {
  if (i == j) return i;
  const int s = i + j;
  return s == 3 ? 3 : (s == 2 ? 4 : 5);
}

// Rotates a stiffness matrix (engineering shear) from the frame whose axes
// are the rows of R to the global frame: C'_ijkl = R_ai R_bj R_ck R_dl C_abcd.
Mat6 rotate_stiffness(const Mat6& C, const Eigen::Matrix3d& R) {
  double c[3][3][3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int e = 0; e < 3; ++e)
        for (int d = 0; d < 3; ++d) c[a][b][e][d] = C(voigt(a, b), voigt(e, d));
  Mat6 out = Mat6::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = k; l < 3; ++l) {
          double s = 0;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              for (int e = 0; e < 3; ++e)
                for (int d = 0; d < 3; ++d)
                  s += R(a, i) * R(b, j) * R(e, k) * R(d, l) * c[a][b][e][d];
          out(voigt(i, j), voigt(k, l)) = s;
        }
  return out;
}

Mat6 isotropic_compliance(double E, double nu) {
  Mat6 S = Mat6::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) S(i, j) = i == j ? 1 / E : -nu / E;
  for (int i = 3; i < 6; ++i) S(i, i) = 2 * (1 + nu) / E;
  return S;
}

// Transversely isotropic compliance with the A axis along local x.
Mat6 transverse_compliance(const MaterialSpec& m) {
  Mat6 S = Mat6::Zero();
  S(0, 0) = 1 / m.EA;
  S(1, 1) = S(2, 2) = 1 / m.ET;
  S(0, 1) = S(1, 0) = S(0, 2) = S(2, 0) = -m.nuA / m.EA;
  S(1, 2) = S(2, 1) = -m.nuT / m.ET;
  S(3, 3) = 2 * (1 + m.nuT) / m.ET;  // transverse-plane shear
  S(4, 4) = S(5, 5) = 1 / m.GA;
  return S;
}

// Orthonormal frame whose first row is the (normalised) axis.
Eigen::Matrix3d frame_from_axis(const Vec3& axis_in) {
  Eigen::Vector3d a(axis_in[0], axis_in[1], axis_in[2]);
  a.normalize();
  Eigen::Vector3d helper =
      std::abs(a.z()) < 0.9 ? Eigen::Vector3d(0, 0, 1) : Eigen::Vector3d(1, 0, 0);
  Eigen::Vector3d b = helper.cross(a).normalized();
  Eigen::Vector3d c = a.cross(b);
  Eigen::Matrix3d R;
  R.row(0) = a;
  R.row(1) = b;
  R.row(2) = c;
  return R;
}

void fill_general(MaterialModel& out, const Mat6& C, int dimension, Plane plane) {
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) out.k.C3[i][j] = C(i, j);
  const int rows[4] = {0, 1, 5, 2}, cols[3] = {0, 1, 5};
  if (dimension == 2 && plane == Plane::stress) {
    // sigma_zz = 0 gives eps_zz as a combination of the in-plane strains.
    double z[3];
    for (int j = 0; j < 3; ++j) z[j] = -C(2, cols[j]) / C(2, 2);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j)
        out.k.C2[i][j] = i == 3 ? 0.0 : C(rows[i], cols[j]) + C(rows[i], 2) * z[j];
    for (int j = 0; j < 3; ++j) out.k.zz_strain[j] = z[j];
  } else {
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) out.k.C2[i][j] = C(rows[i], cols[j]);
  }
}

}  // namespace

MaterialModel make_material(const MaterialSpec& spec, int dimension, Plane plane) {
  MaterialModel out;
  out.name = spec.name;
  out.type = spec.type;
  out.density = spec.density;
  out.k.density = spec.density;
  out.k.plane_stress = dimension == 2 && plane == Plane::stress;
  Mat6 S = Mat6::Zero();
  switch (spec.type) {
    case MaterialType::rigid:
      return out;
    case MaterialType::neohookean:
      if (out.k.plane_stress)
        throw InputError(located(spec.where.file, spec.where.line, "type",
                                 "a neohookean material needs plane = \"strain\" or 3D"));
      [[fallthrough]];
    case MaterialType::isotropic: {
      const double E = spec.E, nu = spec.nu;
      out.k.lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
      out.k.mu = E / (2 * (1 + nu));
      out.k.Ep = E / (1 - nu * nu);
      out.k.nu = nu;
      S = isotropic_compliance(E, nu);
      const double modulus = out.k.plane_stress ? out.k.Ep : out.k.lambda + 2 * out.k.mu;
      out.wave_speed = std::sqrt(modulus / spec.density);
      break;
    }
    case MaterialType::transverse: {
      const Eigen::Matrix3d R = frame_from_axis(spec.axis);
      const Mat6 C = rotate_stiffness(transverse_compliance(spec).inverse(), R);
      fill_general(out, C, dimension, plane);
      S = C.inverse();
      Eigen::SelfAdjointEigenSolver<Mat6> eig(C);
      out.wave_speed = std::sqrt(eig.eigenvalues().maxCoeff() / spec.density);
      break;
    }
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) out.compliance[i][j] = S(i, j);
  return out;
}

Vec3 rigid_velocity(const MaterialSpec& spec, double t) {
  const auto& tab = spec.velocity;
  if (tab.velocity.empty()) return {0, 0, 0};
  if (tab.velocity.size() == 1 || t <= tab.time.front()) return tab.velocity.front();
  for (std::size_t k = 1; k < tab.time.size(); ++k) {
    if (t <= tab.time[k]) {
      const double s = (t - tab.time[k - 1]) / (tab.time[k] - tab.time[k - 1]);
      Vec3 v;
      for (int d = 0; d < 3; ++d) v[d] = (1 - s) * tab.velocity[k - 1][d] + s * tab.velocity[k][d];
      return v;
    }
  }
  return tab.velocity.back();
}

// ∫_0^t of rigid_velocity: the piecewise-linear table integrated exactly,
// each segment by its trapezoid, the end values held before and after it.
Vec3 rigid_displacement(const MaterialSpec& spec, double t) {
  const auto& tab = spec.velocity;
  Vec3 u{0, 0, 0};
  if (tab.velocity.empty() || t <= 0) return u;
  auto add = [&](double t0, double t1) {  // [t0, t1] within [0, t]
    const double a = std::max(t0, 0.0), b = std::min(t1, t);
    if (b <= a) return;
    const Vec3 va = rigid_velocity(spec, a), vb = rigid_velocity(spec, b);
    for (int d = 0; d < 3; ++d) u[d] += 0.5 * (va[d] + vb[d]) * (b - a);
  };
  const double inf = std::numeric_limits<double>::infinity();
  if (tab.velocity.size() == 1) {
    add(-inf, inf);
    return u;
  }
  add(-inf, tab.time.front());
  for (std::size_t k = 1; k < tab.time.size(); ++k) add(tab.time[k - 1], tab.time[k]);
  add(tab.time.back(), inf);
  return u;
}

}  // namespace mmpm
