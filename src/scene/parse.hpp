// Scene files (TOML, SCENE.md) -> resolved Scene.
//
// Every problem in the input throws mmpm::InputError with one message
// "FILE:LINE: key 'PATH': what was expected", where PATH is the dotted key
// ("grid.cell", "material[1].nu"; [i] counts the [[section]] tables from 0).
// A value given by --set is blamed on "--set KEY" instead of FILE:LINE.
//
// Conventions fixed here (the rest of the solver relies on them):
//  - Vectors are stored in Vec3; entries past `dimension` are 0, except
//    grid.cell (1) and grid.cells (1) along the unused z axis of a 2D scene.
//  - Material axis and interaction normal_vector are normalised to length 1.
//  - A rigid material's constant velocity is a one-row table at time 0.
//  - A body's `rotate` (2D only) turns it about the centre of its unrotated
//    bounding box (for a box: its centre; for a polygon: the centre of the
//    box around its points). A cylinder (3D) spans z from center.z to
//    center.z + length.
//  - Body.name defaults to "body<k>" (k = index among the [[body]] tables).
//  - A boundary with a displacement moves its fixed components linearly to it
//    over `ramp` (> 0 required when a displacement is non-zero), then holds.
//  - [stop] present => stop.enabled (unless enabled = false).
//  - output.directory defaults to "results/<scene name>".
//  - source_text is format_scene() of the result: fully resolved TOML that
//    parses back to the same scene.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "scene/error.hpp"
#include "scene/scene.hpp"

namespace mmpm {

// The particle fields [output] fields may name.
inline constexpr std::array<std::string_view, 9> kOutputFieldNames{
    "displacement",        "velocity", "stress", "strain", "material", "body", "mass", "volume",
    "deformation_gradient"};
inline constexpr std::array<std::string_view, 4> kGridFieldNames{"mass", "momentum", "velocity",
                                                                 "force"};

// Reads and validates a scene file; `overrides` are "KEY=VALUE" strings
// from --set, applied in order before validation.
Scene parse_scene_file(const std::string& path, const std::vector<std::string>& overrides = {});

// Same for scene text already in memory; `file_label` names it in messages
// and gives the default scene name (its stem).
Scene parse_scene_text(const std::string& text, const std::string& file_label,
                       const std::vector<std::string>& overrides = {});

}  // namespace mmpm
