// Owning storage for particle and grid columns (flat SoA, one staggered
// array per component; ARCHITECTURE "Data"). Columns are registered by name
// so sorting, checkpoints and output can walk them generically.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kernels/binning.hpp"
#include "model/staggered_array.hpp"

namespace mmpm {

template <class Real>
struct ColumnSet {
  std::vector<std::string> real_names;
  std::vector<StaggeredArray<Real>> reals;
  std::vector<std::string> byte_names;
  std::vector<StaggeredArray<std::uint8_t>> bytes;
  StaggeredArray<std::uint32_t> key;  // binning key (particles only)
  // Seed index (particles only): the particle's row in every output and its
  // number in messages, whatever order the sorts left it in.
  StaggeredArray<std::uint32_t> id;
  int next_slot = 0;

  Real* add_real(const std::string& name, std::size_t n) {
    real_names.push_back(name);
    reals.emplace_back(n, next_slot++);
    return reals.back().data();
  }
  std::uint8_t* add_byte(const std::string& name, std::size_t n) {
    byte_names.push_back(name);
    bytes.emplace_back(n, next_slot++);
    return bytes.back().data();
  }
  std::uint8_t* byte(const std::string& name) {
    for (std::size_t i = 0; i < byte_names.size(); ++i)
      if (byte_names[i] == name) return bytes[i].data();
    return nullptr;
  }
  const std::uint8_t* byte(const std::string& name) const {
    for (std::size_t i = 0; i < byte_names.size(); ++i)
      if (byte_names[i] == name) return bytes[i].data();
    return nullptr;
  }
  Real* real(const std::string& name) {
    for (std::size_t i = 0; i < real_names.size(); ++i)
      if (real_names[i] == name) return reals[i].data();
    return nullptr;
  }
  const Real* real(const std::string& name) const {
    for (std::size_t i = 0; i < real_names.size(); ++i)
      if (real_names[i] == name) return reals[i].data();
    return nullptr;
  }
};

// Every column of a particle store (seed ids, reals, bytes: a ColumnSet or
// the benchmarks' ParticleSet) into the order `perm` gives, after the keys.
// Each thread writes back the rows its loops take in the new order
// (`sorted`, permute_in_place). The scratch vectors grow to n.
template <class Columns, class Real>
void permute_particle_columns(Columns& c, const std::uint32_t* perm, std::size_t n,
                              const TileSchedule& sorted, std::vector<std::uint32_t>& scratch_ids,
                              std::vector<Real>& scratch_reals,
                              std::vector<std::uint8_t>& scratch_bytes) {
  scratch_ids.resize(n);
  permute_in_place(c.id.data(), scratch_ids.data(), perm, n, &sorted);
  scratch_reals.resize(n);
  for (auto& col : c.reals) permute_in_place(col.data(), scratch_reals.data(), perm, n, &sorted);
  scratch_bytes.resize(n);
  for (auto& col : c.bytes) permute_in_place(col.data(), scratch_bytes.data(), perm, n, &sorted);
}

}  // namespace mmpm
