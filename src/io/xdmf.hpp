// run.xdmf: the XML index that lets ParaView (and VisIt) open run.h5 as a
// time series of particle clouds. Pure text generation; the run writer
// decides which datasets exist.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace mmpm::io {

// How ParaView should treat a per-particle field.
//   scalar: 1 component.
//   vector: as many components as the space has dimensions. Both of ParaView's
//           XDMF readers only treat 3-component data as vectors (for Glyph and
//           Warp By Vector), so 2D vectors are referenced through a copy padded
//           with a zero third column.
//   tensor: 9 components in 3D (full row-major tensor, VTK's layout).
//   matrix: anything else, e.g. stress in Voigt order (xx yy [zz] xy ... ):
//           shown as plain numbered components, never reordered. (XDMF's
//           Tensor6 expects xx xy xz yy yz zz, which is not our order.)
enum class AttributeKind { scalar, vector, tensor, matrix };

AttributeKind attribute_kind(int components, int dimension);

struct XdmfField {
  std::string name;
  AttributeKind kind;
  std::string dataset;    // path inside the HDF5 file, e.g. /particles/step_0000000010/velocity
  int stored_components;  // columns of that dataset (3 for a padded 2D vector)
};

struct XdmfSnapshot {
  long step;
  double time;
  int dimension;             // 2 or 3
  std::size_t count;         // particles
  std::string position;      // dataset [count x dimension]
  std::string connectivity;  // dataset [count] of 0..count-1 (one vertex cell per particle)
  std::vector<XdmfField> fields;
};

// One snapshot of the grid's nodal quantities (/grid/step_* in run.h5),
// each dataset shaped [nz,] ny, nx, components.
struct XdmfGridSnapshot {
  long step = 0;
  double time = 0;
  int dimension = 2;
  std::array<std::size_t, 3> nodes{1, 1, 1};  // per direction, x first
  std::array<double, 3> origin{0, 0, 0};
  std::array<double, 3> spacing{1, 1, 1};
  std::vector<XdmfField> fields;
};

// run_grid.xdmf: one temporal collection of structured grids (3DCoRectMesh;
// a 2D grid is one layer of nodes at z = 0, so that ParaView shows it in the
// x-y plane), nodal attributes referenced as "H5_FILE_NAME:/path".
std::string xdmf_grid_document(const std::string& h5_file_name,
                               const std::vector<XdmfGridSnapshot>& snapshots);

// The whole XDMF 3 document: one temporal collection of Polyvertex grids,
// datasets referenced as "H5_FILE_NAME:/path" (relative, so the pair of files
// can be moved together).
std::string xdmf_document(const std::string& h5_file_name,
                          const std::vector<XdmfSnapshot>& snapshots);

}  // namespace mmpm::io
