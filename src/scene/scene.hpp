// The resolved scene: plain data, no behaviour. Parsed from TOML by
// scene/parse.cpp (every field below maps to a key of SCENE.md). Vectors of
// length 3 are used for every dimension; only the first `dimension` entries
// are meaningful.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace mmpm {

using Vec3 = std::array<double, 3>;

enum class Plane { strain, stress };
enum class Scheme { USL, USF, MUSL };
enum class Precision { float64, float32 };
enum class ShapeKind { linear, gimp, bspline2, bspline3 };
enum class MaterialType { isotropic, transverse, neohookean, rigid };
enum class BodyShape { box, disk, sphere, cylinder, polygon };
enum class Law { stick, frictionless, friction, interface, separate };
// geometry: outward normals from the bodies' shapes (model/shape_surface.hpp)
enum class NormalMethod { mvg, avg, specified, radial, rigid, geometry };
// extrapolated: displacement at the node, not at the centroid
// (kernels/separation_extrapolation.hpp)
enum class Separation { displacement, position, extrapolated };
enum class Integration { explicit_, exact };
enum class TractionLaw { linear, bilinear };  // bilinear: stiff in compression (ALGORITHM §3.2)
// The contact area of an interface node: (P-20) on the nodal domains as they are
// (paper) or with the interface's opening closed first (closed, docs/multimaterial.md
// §7.1), or the interface's share of the node read from the domain gradients
// (gradient, §7.2: the one that holds for the B-splines' several node rows).
enum class ContactArea { paper, closed, gradient };
enum class LoadKind { traction, gravity };
enum class ParticleOrder { color, tile };  // storage order of the sorted particles

// A source position for messages ("scene.toml:12: key 'E'").
struct Where {
  std::string file;
  int line = 0;
  std::string key;
};

// Each XPIC term costs an interpolation to the particles and a scatter back
// (about a P2G and a G2P); the measured runs use 2-4, and at 8 terms a
// linear velocity field is kept within 1.8e-3 (docs/validation.md §3.12).
inline constexpr int kMaxXpicOrder = 8;

struct SimulationSpec {
  int dimension = 2;
  Plane plane = Plane::strain;
  double thickness = 1.0;
  double end_time = 0.0;
  double cfl = 0.5;
  std::optional<double> dt;  // explicit time step overrides cfl
  // MUSL by default: USL takes the strain rate from p/m of nodes that may
  // hold a sliver of mass (cell crossing, uGIMP edges) and is unstable there.
  Scheme scheme = Scheme::MUSL;
  double flip = 1.0;
  // XPIC(m) particle velocities (kernels/xpic.hpp): 0 = off (FLIP/PIC by
  // `flip` alone), m >= 1 filters them before the FLIP increment (1 = PIC).
  int xpic_order = 0;  // at most kMaxXpicOrder
  Precision precision = Precision::float64;
  Law default_law = Law::stick;
  bool force = false;  // run even when dt exceeds the stability limit
  int sort_every = 0;  // 0 = re-bin only when a particle changes tile
  // true: the constitutive update runs inside the G2P gradient pass (one
  // particle pass fewer) when every stressed material is isotropic. Off by
  // default: measured slower for 2D linear and no faster for 2D uGIMP
  // (docs/performance.md, "Fusing the constitutive update").
  bool fuse_constitutive = false;
  // float only: positions keep their rounding error in a second array
  // (kernels/position_sum.hpp), so a step's move below half an ulp of x
  // is not lost. false: plain float sums, 3-7 % faster steps whose static
  // displacements stop short (docs/performance.md "Positions in float").
  bool compensated_positions = true;
  // MUSL: the gradient G2P, the constitutive update and the next step's
  // P2G run tile by tile in one pass, so P2G reads particle columns still
  // in the cache; same particle results, bitwise (docs/performance.md
  // "The step's tail fused tile by tile"). false: three separate passes.
  bool fuse_step_tail = true;
  // The node passes (zeroing, momentum update, velocities, supports) visit
  // only the nodes each velocity field's particles can reach; same results,
  // bitwise (docs/performance.md "Node passes over the nodes a field can
  // reach"). false: every node of every field.
  bool skip_empty_nodes = true;
  // 2D transfers request the grid lines their windows reach next, a line
  // ahead in x; same results, bitwise (kernels/grid_prefetch.hpp,
  // docs/performance.md "Grid lines a line ahead"). false: no requests.
  bool prefetch_grid = true;
  // The transfers request the particle columns they stream a batch ahead;
  // same results, bitwise (kernels/particle_prefetch.hpp, docs/performance.md
  // "Particle columns requested ahead"). false: no requests.
  bool prefetch_particles = true;
  // How the particles are stored between sorts: tile by tile, color by color
  // (each colored pass reads its particles front to back), or in plain tile
  // order. Same results but for the order of sums over particles
  // (docs/performance.md "Particles stored color by color").
  ParticleOrder particle_order = ParticleOrder::color;
  // The multimaterial fields (mx, Omega, g) are scattered apart, only from
  // tiles that reach a multimaterial node, unless more than this share of
  // the particles sits in such tiles (then with the first P2G). The values
  // at multimaterial nodes are the same either way (docs/performance.md,
  // "Multimaterial fields where they are read").
  double mm_fields_share = 0.5;
  Where step_where;         // where the time step was set (cfl or dt), for messages
  Where default_law_where;  // where default_law was set (line 0: not in the file)
};

struct GridSpec {
  Vec3 origin{0, 0, 0};
  Vec3 cell{1, 1, 1};
  std::array<int, 3> cells{1, 1, 1};
  ShapeKind shape = ShapeKind::gimp;
  double damping = 0.0;  // 1/time
  int tile = 0;          // tile edge in cells for the colored scatter; 0 = automatic
};

// Time table for a rigid material's velocity: piecewise linear, held after the last row.
struct VelocityTable {
  std::vector<double> time;
  std::vector<Vec3> velocity;
};

struct MaterialSpec {
  std::string name;
  MaterialType type = MaterialType::isotropic;
  double density = 1.0;
  double E = 0, nu = 0;                             // isotropic, neohookean
  double EA = 0, ET = 0, GA = 0, nuA = 0, nuT = 0;  // transverse
  Vec3 axis{0, 1, 0};                               // transverse: the A (fibre) axis
  VelocityTable velocity;                           // rigid (one row = constant)
  Where where;
};

struct BodySpec {
  std::string name;
  std::string material;
  BodyShape shape = BodyShape::box;
  Vec3 min{0, 0, 0}, max{0, 0, 0};  // box
  double rotate = 0.0;              // degrees about the body's centre (2D)
  std::optional<Vec3>
      pivot;             // rotate about this point instead (a whole specimen of several bodies)
  Vec3 center{0, 0, 0};  // disk, sphere, cylinder
  double radius = 0.0;
  double length = 0.0;         // cylinder (3D): from center along `axis`
  Vec3 axis{0, 0, 1};          // cylinder: unit direction
  std::vector<Vec3> points;    // polygon
  int particles_per_cell = 2;  // per direction
  Vec3 velocity{0, 0, 0};
  std::optional<std::pair<Vec3, Vec3>> clip;  // fill only inside this box
  Where where;
};

struct InteractionSpec {
  std::array<std::string, 2> materials;
  Law law = Law::stick;
  double friction = 0.0;
  double Dn = 0.0, Dt = 0.0;  // MPa/mm; +inf = "perfect"
  TractionLaw traction_law = TractionLaw::linear;
  double Dn_compression = std::numeric_limits<double>::infinity();  // bilinear
  NormalMethod normal = NormalMethod::mvg;
  Vec3 normal_vector{1, 0, 0};
  Vec3 center{0, 0, 0};       // radial
  Vec3 radial_axis{0, 0, 0};  // radial in 3D about a line (unit), or 0: about the point `center`
  Separation separation = Separation::displacement;
  double min_volume = 0.0;      // fraction of the cell volume
  double contact_offset = 0.8;  // δ_con / h⊥, position separation only (P-14)
  bool force_limit = true;
  Integration integration = Integration::explicit_;
  ContactArea area = ContactArea::paper;  // interface law only
  Where where;
};

// An interface with a spring that reads the particles' displacements: a
// finite Dn or Dt (or the bilinear law's compression stiffness), and not the
// position method, which reads x. A perfect interface has no spring.
inline bool has_displacement_spring(const InteractionSpec& it) {
  if (it.law != Law::interface || it.separation == Separation::position) return false;
  const bool compression_spring =
      it.traction_law == TractionLaw::bilinear && std::isfinite(it.Dn_compression);
  return std::isfinite(it.Dn) || std::isfinite(it.Dt) || compression_spring;
}

enum class BoundaryWhere { face, plane, box };

struct BoundarySpec {
  BoundaryWhere kind = BoundaryWhere::face;
  int face_axis = 0;      // face: 0,1,2
  bool face_max = false;  // face: min or max side
  int plane_axis = 0;     // plane: { x = value }
  double plane_value = 0;
  Vec3 box_min{0, 0, 0}, box_max{0, 0, 0};
  std::array<bool, 3> fix{false, false, false};
  Vec3 displacement{0, 0, 0};  // prescribed displacement of the fixed components
  double ramp = 0.0;           // time over which `displacement` is reached; 0 = at once? see parse
  bool has_displacement = false;
  std::string label;  // e.g. "y_min" — used to name the reaction force in the series
  Where where;
};

struct LoadSpec {
  LoadKind kind = LoadKind::traction;
  std::string body;   // traction
  int face_axis = 0;  // traction: face of the body ("x_min" ...)
  bool face_max = false;
  Vec3 traction{0, 0, 0};      // in the body's frame
  Vec3 acceleration{0, 0, 0};  // gravity
  double ramp = 0.0;
  Where where;
};

struct OutputSpec {
  double every = 0.0;  // time between particle snapshots; 0 = only the last
  std::vector<std::string> fields{"displacement", "velocity", "stress", "material"};
  // Nodal quantities written with every snapshot (SCENE.md "grid fields on
  // request"): none by default.
  std::vector<std::string> grid_fields;
  int series = 100;               // steps between series rows
  double checkpoint_minutes = 0;  // wall minutes between checkpoints; 0 = none
  std::string directory;          // default results/<scene name>
  Where directory_where;          // the key, when the scene sets it (messages)
};

struct StopSpec {
  bool enabled = false;
  double kinetic_ratio = 1e-8;
  int hold_steps = 1000;
};

struct Scene {
  std::string name;  // from the file name (stem) unless [simulation] name
  std::string source_file;
  std::string source_text;  // resolved TOML (after --set), stored with results
  SimulationSpec simulation;
  GridSpec grid;
  std::vector<MaterialSpec> materials;
  std::vector<BodySpec> bodies;
  std::vector<InteractionSpec> interactions;
  std::vector<BoundarySpec> boundaries;
  std::vector<LoadSpec> loads;
  OutputSpec output;
  StopSpec stop;

  // Index into `materials` of the material called `material_name`, or -1.
  int material_index(const std::string& material_name) const {
    for (std::size_t m = 0; m < materials.size(); ++m)
      if (materials[m].name == material_name) return int(m);
    return -1;
  }
};

}  // namespace mmpm
