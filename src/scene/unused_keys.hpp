// Warnings for [[interaction]] keys the chosen law or normal never reads
// (law = "stick" with Dn = 5, law = "frictionless" with friction = 0.3,
// normal = "mvg" with a normal_vector): the run would silently do something
// else than the file seems to say. A key warns when its value differs from
// the default, so the resolved scene (which writes every key, and which
// --restart compares byte for byte with the checkpoint's copy) warns exactly
// when the file it came from did.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

std::vector<std::string> unused_interaction_key_warnings(const Scene& scene);

}  // namespace mmpm
