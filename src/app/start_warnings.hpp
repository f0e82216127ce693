// The scene warnings `check` and `run` print before a fresh start, one line
// each, in one order: interaction keys the law or normal never reads
// (scene/unused_keys.hpp), USL above its measured step limit, interfaces too
// stiff for the step without the force limit, contact pairs that start
// apart under the displacement separation, the position separation on
// bodies that start bonded, the extrapolated separation with 1 particle
// per cell, computed normals on an interface with a perfect direction and
// no edge screening.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

class Simulation;

std::vector<std::string> start_warnings(const Scene& scene, const Simulation& sim, double dt);

}  // namespace mmpm
