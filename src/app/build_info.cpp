#include "app/build_info.hpp"

#include <hdf5.h>
#include <omp.h>
#include <tbb/version.h>

#include <Eigen/Core>
#include <sstream>
#include <thread>

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
