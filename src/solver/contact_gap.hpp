// Contact pairs that start apart while their interaction uses the
// displacement separation (ALGORITHM §3: "requires the bodies to touch in
// the initial state"). With it, δ_n is the difference of displacements,
// 0 at the start whatever the gap, so two approaching materials count as in
// contact as soon as their particles reach a common node: a cell or more
// before their surfaces meet. A rigid punch seeded 0.05 mm above a block
// (0.1 mm cells) pushed it from the first step. Said as a warning by
// `check` and `run`, since a scene may mean it.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

class Simulation;

// One warning per pair of velocity fields under a contact law (stick,
// frictionless, friction; an [[interaction]] or [simulation] default_law,
// not two rigid fields) with separation = "displacement" whose particles
// have no pair closer than 1.5 mean particle spacings (spacing: cell /
// particles_per_cell, the largest over directions and over the fields'
// bodies) in the simulation's current (initial) state:
// "FILE:LINE: warning: key 'interaction[i].separation': ..." or
// "FILE[:LINE]: warning: key 'simulation.default_law' (...): ..." (LINE
// when the scene sets default_law).
std::vector<std::string> open_contact_warnings(const Scene& scene, const Simulation& sim);

// The opposite misuse: an interface (law = "interface") between materials
// whose particles start touching, with separation = "position". The
// position method measures the opening from the two materials' centroids
// at a node, which for bonded bodies lie ~0.75 cell apart (2 particles per
// cell), less the contact offset: the interface starts loaded. two_layer.toml
// with Dn = 1000 made 5.2 mJ of energy from 0.0019 mJ of work in 0.01 ms.
// "FILE:LINE: warning: key 'interaction[i].separation': ...".
std::vector<std::string> bonded_position_interface_warnings(const Scene& scene,
                                                            const Simulation& sim);

}  // namespace mmpm
