#include "app/build_info.hpp"

#include <hdf5.h>
#include <omp.h>
#include <tbb/version.h>

#include <Eigen/Core>
#include <sstream>
#include <thread>

#include "kernels/packed_linear.hpp"

namespace mmpm {

std::string build_description() {
  std::ostringstream os;
  os << "mmpm " << MMPM_VERSION << "\n";
  os << "compiler: g++ " << __VERSION__ << "\n";
#if defined(__AVX512F__)
  os << "simd: AVX-512 (512-bit)\n";
#elif defined(__AVX2__)
  os << "simd: AVX2 (256-bit)\n";
#elif defined(__SSE2__)
  os << "simd: SSE2 (128-bit)\n";
#else
  os << "simd: none\n";
#endif
  // Which 2D linear transfers run: the packed ones (several particles per
  // register) need AVX-512; an AVX2 build's 2D linear step is 1.34x slower
  // on the same core (docs/performance.md "The AVX2 build on the AVX-512
  // host"), so a user comparing machines should see which one runs.
  constexpr int packed_double = packed_particles<2, LinearShape, double>();
  constexpr int packed_float = packed_particles<2, LinearShape, float>();
  if constexpr (packed_double > 1)
    os << "2d linear kernels: packed (" << packed_double << " particles per vector in double, "
       << packed_float << " in float)\n";
  else
    os << "2d linear kernels: one particle per vector (the packed kernels need AVX-512)\n";
  os << "openmp: " << _OPENMP << ", max threads " << omp_get_max_threads() << "\n";
  os << "hardware threads: " << std::thread::hardware_concurrency() << "\n";
  os << "eigen: " << EIGEN_WORLD_VERSION << "." << EIGEN_MAJOR_VERSION << "." << EIGEN_MINOR_VERSION
     << "\n";
  os << "tbb: " << TBB_VERSION_MAJOR << "." << TBB_VERSION_MINOR << "\n";
  unsigned maj = 0, min = 0, rel = 0;
  H5get_libversion(&maj, &min, &rel);
  os << "hdf5: " << maj << "." << min << "." << rel << "\n";
#ifdef MMPM_FAST_DEV
  os << "instantiations: 2D linear double, 2D gimp double/float, 3D gimp double (MMPM_FAST_DEV "
        "build)\n";
#else
  os << "instantiations: dimension {2,3} x shape {linear, gimp, bspline2, bspline3} x precision "
        "{double, float}\n";
#endif
  return os.str();
}

}  // namespace mmpm
