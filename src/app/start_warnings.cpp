#include "app/start_warnings.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "kernels/shape.hpp"
#include "model/bodies.hpp"
#include "scene/format.hpp"
#include "scene/interaction_warning.hpp"
#include "scene/unused_keys.hpp"
#include "solver/contact_gap.hpp"
#include "solver/simulation.hpp"

namespace mmpm {

namespace {

// kernels/separation_extrapolation.hpp: with 1 particle per cell the
// extrapolation has too little spread to work with at a curved interface
// (docs/interface_validation.md, "Extrapolated separation").
std::vector<std::string> extrapolated_separation_warnings(const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    if (it.separation != Separation::extrapolated) continue;
    for (const BodySpec& b : scene.bodies) {
      if (b.particles_per_cell >= 2 ||
          (b.material != it.materials[0] && b.material != it.materials[1]))
        continue;
      std::ostringstream m;
      m << interaction_warning(scene, k, "separation")
        << "\"extrapolated\" needs 2 or more particles per cell per direction; "
        << "body '" << b.name << "' has " << b.particles_per_cell
        << " (a sphere in a cube seeded 1 per cell blew up at D = 1e6 MPa/mm where "
        << "\"displacement\" only crept)";
      out.push_back(m.str());
    }
  }
  return out;
}

// The paper's §2.5 (Figs. 10, 11, conclusions): where an interface meets a
// free edge the volume gradients of both materials tilt by up to 45°, and a
// perfect direction locks that wrong normal. Measured on
// inputs/series_bars.toml (Dn = 10, Dt perfect, a 4-cell-wide bar):
// mvg 1.2 % of the exact interface energy, avg exact on that grid-line
// interface, mvg with min_volume = 0.75 +33 % (the screened edge nodes
// take their area with them) (docs/interface_validation.md, Finding 9).
std::vector<std::string> computed_normal_warnings(const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    const bool computed = it.normal == NormalMethod::mvg || it.normal == NormalMethod::avg;
    const bool perfect = std::isinf(it.Dn) || std::isinf(it.Dt);
    if (it.law != Law::interface || !computed || !perfect || it.min_volume > 0) continue;
    std::ostringstream m;
    m << interaction_warning(scene, k, "normal") << "normal = \"" << scene_name(it.normal) << "\""
      << (it.normal == NormalMethod::mvg ? " (mvg is the default)" : "") << " with D"
      << (std::isinf(it.Dn) ? 'n' : 't')
      << " = \"perfect\" and min_volume = 0: where the interface meets a free edge the "
         "computed normal tilts by up to 45 degrees and the perfect direction locks it "
         "(paper 2.5, Figs. 10-11; series_bars with mvg reads 1.2 % of the exact interface "
         "energy); give a \"specified\" or \"radial\" normal where the geometry has one, "
         "or screen edge nodes with min_volume (0.75 at a grid line, 0.85 at a midplane)";
    out.push_back(m.str());
  }
  return out;
}

// The first axis along which body b is thinner than `cells` cells and has a
// body of material `partner` beside both of its faces (within `reach` cells
// of the face, overlapping b across the other axes); -1 if none.
int thin_between_partners(const Scene& scene, const BodySpec& b, const std::string& partner,
                          double cells, double reach) {
  const int dim = scene.simulation.dimension;
  const auto [lo, hi] = body_bounds(b, dim);
  for (int d = 0; d < dim; ++d) {
    const double h = scene.grid.cell[d];
    if (hi[d] - lo[d] >= cells * h) continue;
    bool below = false, above = false;
    for (const BodySpec& p : scene.bodies) {
      if (p.material != partner) continue;
      const auto [plo, phi] = body_bounds(p, dim);
      bool across = true;
      for (int e = 0; e < dim; ++e)
        if (e != d && (phi[e] <= lo[e] || plo[e] >= hi[e])) across = false;
      if (!across) continue;
      below = below || (plo[d] < lo[d] && phi[d] > lo[d] - reach * h);
      above = above || (phi[d] > hi[d] && plo[d] < hi[d] + reach * h);
    }
    if (below && above) return d;
  }
  return -1;
}

// docs/multimaterial.md §7.2. (P-20) gives every row of interface nodes a full
// share, and the B-splines put an interface in three rows: the series bars
// read U_int 0.740 (bspline2) and 0.650 (bspline3) of the exact value. The
// gradient area (their default) reads the share of each row; but where one
// node sees the same partner across both faces of a thin body, the two
// faces' shares cancel: the double lap shear with a 2-cell central lap reads
// U_int +20 % (bspline2) and +28 % (bspline3), with a 4-cell lap -1 %.
std::vector<std::string> bspline_area_warnings(const Scene& scene) {
  std::vector<std::string> out;
  const ShapeKind shape = scene.grid.shape;
  if (shape != ShapeKind::bspline2 && shape != ShapeKind::bspline3) return out;
  const double reach = shape == ShapeKind::bspline2 ? 1.5 : 2.0;  // cells
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    if (it.law != Law::interface) continue;
    if (it.area != ContactArea::gradient) {
      std::ostringstream m;
      m << interaction_warning(scene, k, "area") << "area = \"" << scene_name(it.area) << "\" with "
        << scene_name(shape)
        << " shape functions: (P-20) gives each of the two or three rows of nodes a "
           "B-spline puts an interface in a full share (the series bars read the interface "
           "energy at "
        << (shape == ShapeKind::bspline2 ? "0.74" : "0.65")
        << " of the exact value); \"gradient\", the B-splines' default, reads each row's share";
      out.push_back(m.str());
      continue;
    }
    for (const BodySpec& b : scene.bodies) {
      if (b.material != it.materials[0] && b.material != it.materials[1]) continue;
      const std::string& partner =
          b.material == it.materials[0] ? it.materials[1] : it.materials[0];
      const int d = thin_between_partners(scene, b, partner, 2 * reach, reach);
      if (d < 0) continue;
      const auto [lo, hi] = body_bounds(b, scene.simulation.dimension);
      std::ostringstream m;
      m << interaction_warning(scene, k, "area") << "body '" << b.name << "' is "
        << format_number((hi[d] - lo[d]) / scene.grid.cell[d]) << " cells thick along "
        << "xyz"[d] << ", less than the " << format_number(2 * reach) << " cells "
        << scene_name(shape) << " needs, with '" << partner
        << "' on both faces: nodes between them see both faces, and their "
        << "shares of the gradient area cancel (a double lap shear with a 2-cell central "
           "lap reads the interface energy +20 % with bspline2, with a 4-cell lap -1 %); "
           "refine the grid";
      out.push_back(m.str());
    }
  }
  return out;
}

// Where two bodies meet on a grid line, each one's particles that reach a
// node on it have their mass centroid c(shape, n) h from it: the weights
// (kernels/shape.hpp, uGIMP with the half-width of n per cell) of the rows
// seeded n per cell within two cells of the node. The position method reads
// the pair as c_a + c_b apart; below contact_offset it registers contact.
// Linear and uGIMP at 2 per cell: 0.75 (the paper's 0.8 sits above it);
// 1 per cell, and every B-spline case, lie above 0.8
// (docs/contact_validation.md §11).
template <class Shape>
double touching_centroid_distance(int per_cell) {
  const double half_width = 0.5 / per_cell;
  double sum = 0, moment = 0;
  for (int k = 0; k < 2 * per_cell; ++k) {
    const double x = (k + 0.5) / per_cell;  // the row's distance from the node
    double w[Shape::S], dw[Shape::S];
    const int base = Shape::eval(x, half_width, w, dw);  // node 0 is window entry -base
    if (base > 0 || -base >= Shape::S) continue;
    sum += w[-base];
    moment += w[-base] * x;
  }
  return moment / sum;
}

double touching_centroid_distance(ShapeKind shape, int per_cell) {
  switch (shape) {
    case ShapeKind::linear:
      return touching_centroid_distance<LinearShape>(per_cell);
    case ShapeKind::gimp:
      return touching_centroid_distance<GimpShape>(per_cell);
    case ShapeKind::bspline2:
      return touching_centroid_distance<BSpline2Shape>(per_cell);
    case ShapeKind::bspline3:
      return touching_centroid_distance<BSpline3Shape>(per_cell);
  }
  return 0;
}

std::vector<std::string> position_offset_warnings(const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    if (it.separation != Separation::position || it.law == Law::interface ||
        it.law == Law::separate)
      continue;
    double reach[2] = {0, 0};  // the largest centroid distance of each material's bodies
    for (const BodySpec& b : scene.bodies)
      for (int side = 0; side < 2; ++side)
        if (b.material == it.materials[std::size_t(side)])
          reach[side] = std::max(
              reach[side], touching_centroid_distance(scene.grid.shape, b.particles_per_cell));
    const double gap = reach[0] + reach[1];
    if (reach[0] == 0 || reach[1] == 0 || it.contact_offset >= gap) continue;
    std::ostringstream m;
    m.precision(3);
    m << interaction_warning(scene, k, "contact_offset") << "with shape \""
      << scene_name(scene.grid.shape) << "\" and these bodies' particles per cell, the "
      << "particles of two flush faces have their centroids " << gap
      << " h apart at a node on the faces, above contact_offset = " << it.contact_offset
      << ": the position method registers contact only once the faces overlap by "
      << gap - it.contact_offset
      << " h (a rigid platen pressed 0.04 h into a block with bspline2 read no reaction); "
         "raise contact_offset to "
      << gap + 0.05 << ", or use separation = \"displacement\" for bodies that start touching";
    out.push_back(m.str());
  }
  return out;
}

// Whether a box or polygon body has a face at an angle to the grid: its
// particles then fill that face as a staircase.
bool has_slanted_face(const BodySpec& b) {
  const double turn = std::remainder(b.rotate, 90.0);
  if (b.shape == BodyShape::box) return turn != 0.0;
  if (b.shape != BodyShape::polygon) return false;
  const BodyFrame frame(b);
  for (std::size_t i = 0, j = b.points.size() - 1; i < b.points.size(); j = i++) {
    const Vec3 e =
        frame.to_global({b.points[i][0] - b.points[j][0], b.points[i][1] - b.points[j][1], 0.0});
    const double tol = 1e-9 * std::hypot(e[0], e[1]);
    if (std::abs(e[0]) > tol && std::abs(e[1]) > tol) return true;
  }
  return false;
}

// docs/contact_validation.md §4.4: the normals computed from the particles
// of a slanted face scatter by up to 25° from node to node, and a contact
// stops or slows a slide along it (a 20° incline of rotated boxes,
// frictionless: mvg -0.009, avg -0.004, rigid 13.8 against 34.2 mm/ms^2).
// normal = "geometry" reads that face from the body (§18).
std::vector<std::string> slanted_face_warnings(const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    const bool contact =
        it.law == Law::stick || it.law == Law::frictionless || it.law == Law::friction;
    const bool computed = it.normal == NormalMethod::mvg || it.normal == NormalMethod::avg ||
                          it.normal == NormalMethod::rigid;
    if (!contact || !computed) continue;
    for (const BodySpec& b : scene.bodies) {
      if (b.material != it.materials[0] && b.material != it.materials[1]) continue;
      if (!has_slanted_face(b)) continue;
      std::ostringstream w;
      w << interaction_warning(scene, k, "normal") << "normal = \"" << scene_name(it.normal)
        << "\" on body '" << b.name
        << "', which has a face at an angle to the grid: its particles fill that face as a "
           "staircase, the computed normals scatter around the face's, and contact stops or "
           "slows a slide along it (a 20-degree incline of rotated boxes, frictionless: mvg "
           "-0.009, rigid 13.8 against 34.2 mm/ms^2); normal = \"geometry\" takes the normals "
           "from the bodies' shapes";
      out.push_back(w.str());
      break;
    }
  }
  return out;
}

// docs/validation.md §3.11 (open): USF with linear shapes grows without
// bound where rows of particles cross grid lines under load, at every step
// size tried (a block at rest on a support under gravity, cfl 0.1 to 0.5).
std::string usf_linear_warning(const Scene& scene) {
  if (scene.simulation.scheme != Scheme::USF || scene.grid.shape != ShapeKind::linear) return {};
  return scene.source_file +
         ": warning: key 'simulation.scheme': \"USF\" with shape \"linear\" goes unstable where "
         "rows of particles cross grid lines under load (a block at rest on a support under "
         "gravity stopped by 1 ms at every cfl from 0.1 to 0.5): USF reads the strain of a "
         "motion in the cell a particle ended in, not the one it moved through "
         "(docs/validation.md §3.11); scheme \"MUSL\" or shape \"gimp\" runs it";
}

// docs/interface_validation.md Findings 14 and 15: with FLIP, MUSL without the
// force limit and USF read the interface's opening from a motion other than
// the one their strain reads, and an undamped vibration across the spring
// gains energy (two bonded bars at Dn = 100 MPa/mm: 3.2 and 3.1 E0 in 3 ms).
// MUSL under the limit or the exact integration keeps it (1.03); grid damping
// settles it; USL and pure PIC lose it.
std::vector<std::string> undamped_interface_growth_warnings(const Scene& scene) {
  std::vector<std::string> out;
  const SimulationSpec& sim = scene.simulation;
  if (scene.grid.damping > 0 || !(sim.flip > 0) || sim.scheme == Scheme::USL) return out;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    if (!has_displacement_spring(it)) continue;
    std::ostringstream m;
    if (sim.scheme == Scheme::USF) {
      m << interaction_warning(scene, k, "law")
        << "an interface spring under scheme \"USF\" with no grid damping: an undamped "
           "vibration across it gains energy (two bonded bars at Dn = 100 MPa/mm: 3.1 times "
           "their energy in 3 ms; docs/interface_validation.md Finding 15); scheme \"MUSL\" "
           "keeps it (1.03), grid.damping settles it";
    } else if (!it.force_limit && it.integration == Integration::explicit_) {
      m << interaction_warning(scene, k, "force_limit")
        << "force_limit = false with no grid damping: under MUSL an undamped vibration across "
           "this interface gains energy (two bonded bars at Dn = 100 MPa/mm: 3.2 times their "
           "energy in 3 ms; docs/interface_validation.md Finding 14); force_limit = true (the "
           "default) or integration = \"exact\" keeps it (1.03), grid.damping settles it";
    } else {
      continue;
    }
    out.push_back(m.str());
  }
  return out;
}

}  // namespace

std::vector<std::string> start_warnings(const Scene& scene, const Simulation& sim, double dt) {
  std::vector<std::string> out = unused_interaction_key_warnings(scene);
  if (std::string w = usl_time_step_warning(scene, dt); !w.empty()) out.push_back(std::move(w));
  if (std::string w = usf_linear_warning(scene); !w.empty()) out.push_back(std::move(w));
  for (std::string& w : stiff_interface_warnings(scene, dt)) out.push_back(std::move(w));
  for (std::string& w : open_contact_warnings(scene, sim)) out.push_back(std::move(w));
  for (std::string& w : bonded_position_interface_warnings(scene, sim)) out.push_back(std::move(w));
  for (std::string& w : extrapolated_separation_warnings(scene)) out.push_back(std::move(w));
  for (std::string& w : computed_normal_warnings(scene)) out.push_back(std::move(w));
  for (std::string& w : position_offset_warnings(scene)) out.push_back(std::move(w));
  for (std::string& w : slanted_face_warnings(scene)) out.push_back(std::move(w));
  for (std::string& w : bspline_area_warnings(scene)) out.push_back(std::move(w));
  for (std::string& w : undamped_interface_growth_warnings(scene)) out.push_back(std::move(w));
  return out;
}

}  // namespace mmpm
