// The resolved scene as text, and the scene-file spelling of every enum.
//
// format_scene() writes valid TOML in the scene-file syntax of SCENE.md with
// every value spelled out (defaults included), so the same text is what
// `mmpm check` prints and what a run stores to be reproduced exactly
// (parse_scene_text(format_scene(s)) gives back s).
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>

#include "scene/scene.hpp"

namespace mmpm {

// One enum value and the word a scene file uses for it.
template <class E>
struct EnumName {
  std::string_view name;
  E value;
};

inline constexpr std::array<EnumName<Plane>, 2> kPlaneNames{
    {{"strain", Plane::strain}, {"stress", Plane::stress}}};
inline constexpr std::array<EnumName<Scheme>, 3> kSchemeNames{
    {{"USL", Scheme::USL}, {"USF", Scheme::USF}, {"MUSL", Scheme::MUSL}}};
inline constexpr std::array<EnumName<Precision>, 2> kPrecisionNames{
    {{"double", Precision::float64}, {"float", Precision::float32}}};
inline constexpr std::array<EnumName<ShapeKind>, 4> kShapeKindNames{
    {{"linear", ShapeKind::linear},
     {"gimp", ShapeKind::gimp},
     {"bspline2", ShapeKind::bspline2},
     {"bspline3", ShapeKind::bspline3}}};
inline constexpr std::array<EnumName<MaterialType>, 4> kMaterialTypeNames{
    {{"isotropic", MaterialType::isotropic},
     {"transverse", MaterialType::transverse},
     {"neohookean", MaterialType::neohookean},
     {"rigid", MaterialType::rigid}}};
inline constexpr std::array<EnumName<BodyShape>, 5> kBodyShapeNames{
    {{"box", BodyShape::box},
     {"disk", BodyShape::disk},
     {"sphere", BodyShape::sphere},
     {"cylinder", BodyShape::cylinder},
     {"polygon", BodyShape::polygon}}};
inline constexpr std::array<EnumName<Law>, 5> kLawNames{{{"stick", Law::stick},
                                                         {"frictionless", Law::frictionless},
                                                         {"friction", Law::friction},
                                                         {"interface", Law::interface},
                                                         {"separate", Law::separate}}};
// [simulation] default_law applies to pairs without an [[interaction]], which
// have nowhere to give a friction coefficient or interface stiffnesses.
inline constexpr std::array<EnumName<Law>, 3> kDefaultLawNames{
    {{"stick", Law::stick}, {"frictionless", Law::frictionless}, {"separate", Law::separate}}};
inline constexpr std::array<EnumName<NormalMethod>, 6> kNormalMethodNames{
    {{"mvg", NormalMethod::mvg},
     {"avg", NormalMethod::avg},
     {"specified", NormalMethod::specified},
     {"radial", NormalMethod::radial},
     {"rigid", NormalMethod::rigid},
     {"geometry", NormalMethod::geometry}}};
inline constexpr std::array<EnumName<Separation>, 3> kSeparationNames{
    {{"displacement", Separation::displacement},
     {"position", Separation::position},
     {"extrapolated", Separation::extrapolated}}};
inline constexpr std::array<EnumName<Integration>, 2> kIntegrationNames{
    {{"explicit", Integration::explicit_}, {"exact", Integration::exact}}};
inline constexpr std::array<EnumName<TractionLaw>, 2> kTractionLawNames{
    {{"linear", TractionLaw::linear}, {"bilinear", TractionLaw::bilinear}}};
inline constexpr std::array<EnumName<ContactArea>, 3> kContactAreaNames{
    {{"paper", ContactArea::paper},
     {"closed", ContactArea::closed},
     {"gradient", ContactArea::gradient}}};
inline constexpr std::array<EnumName<LoadKind>, 2> kLoadKindNames{
    {{"traction", LoadKind::traction}, {"gravity", LoadKind::gravity}}};
inline constexpr std::array<EnumName<ParticleOrder>, 2> kParticleOrderNames{
    {{"color", ParticleOrder::color}, {"tile", ParticleOrder::tile}}};

// The full table for each enum, found by overload on a value of the enum type.
constexpr std::span<const EnumName<Plane>> enum_names(Plane) {
  return kPlaneNames;
}
constexpr std::span<const EnumName<Scheme>> enum_names(Scheme) {
  return kSchemeNames;
}
constexpr std::span<const EnumName<Precision>> enum_names(Precision) {
  return kPrecisionNames;
}
constexpr std::span<const EnumName<ShapeKind>> enum_names(ShapeKind) {
  return kShapeKindNames;
}
constexpr std::span<const EnumName<MaterialType>> enum_names(MaterialType) {
  return kMaterialTypeNames;
}
constexpr std::span<const EnumName<BodyShape>> enum_names(BodyShape) {
  return kBodyShapeNames;
}
constexpr std::span<const EnumName<Law>> enum_names(Law) {
  return kLawNames;
}
constexpr std::span<const EnumName<NormalMethod>> enum_names(NormalMethod) {
  return kNormalMethodNames;
}
constexpr std::span<const EnumName<Separation>> enum_names(Separation) {
  return kSeparationNames;
}
constexpr std::span<const EnumName<Integration>> enum_names(Integration) {
  return kIntegrationNames;
}
constexpr std::span<const EnumName<TractionLaw>> enum_names(TractionLaw) {
  return kTractionLawNames;
}
constexpr std::span<const EnumName<ContactArea>> enum_names(ContactArea) {
  return kContactAreaNames;
}
constexpr std::span<const EnumName<LoadKind>> enum_names(LoadKind) {
  return kLoadKindNames;
}
constexpr std::span<const EnumName<ParticleOrder>> enum_names(ParticleOrder) {
  return kParticleOrderNames;
}

// The scene-file word for an enum value: scene_name(Scheme::USL) == "USL".
template <class E>
constexpr std::string_view scene_name(E value) {
  for (const auto& entry : enum_names(value)) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

// Grid/body faces: "x_min" .. "z_max" <-> (axis, max side).
std::string face_name(int axis, bool max_side);

// The shortest text that reads back as exactly `x` ("0.4", "1e-08", "2400").
// No forced decimal point: use format_toml_float() where TOML must see a float.
std::string format_number(double x);

// format_number() plus ".0" when needed so TOML reads a float, not an integer.
std::string format_toml_float(double x);

// "[x, y]" or "[x, y, z]": the first `dim` entries by format_number(), for messages.
std::string format_vector(const Vec3& v, int dim);

// The resolved scene as TOML: every section and key, defaults included.
std::string format_scene(const Scene& scene);

}  // namespace mmpm
