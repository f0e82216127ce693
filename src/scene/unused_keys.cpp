#include "scene/unused_keys.hpp"

#include <cmath>

#include "scene/format.hpp"
#include "scene/interaction_warning.hpp"

namespace mmpm {

namespace {

std::string stiffness_text(double d) {
  return std::isinf(d) ? "\"perfect\"" : format_number(d);
}

// The scene-file word of an enum value, in quotes: "\"stick\"".
template <class E>
std::string quoted_word(E value) {
  return "\"" + std::string(scene_name(value)) + "\"";
}

}  // namespace

std::vector<std::string> unused_interaction_key_warnings(const Scene& scene) {
  std::vector<std::string> out;
  const InteractionSpec defaults;
  const int dim = scene.simulation.dimension;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    const std::string law = "law = " + quoted_word(it.law);
    const auto warn = [&](const char* key, const std::string& value, const std::string& why) {
      out.push_back(interaction_warning(scene, k, key) + key + " = " + value +
                    " has no effect: " + why);
    };
    // The interface's own keys (ALGORITHM §4: the stiffnesses, the traction
    // law, its force limit and integration) are read by law = "interface"
    // only; `area` outside that law is already an error (parse.cpp).
    if (it.law != Law::interface) {
      const std::string why = law + " does not read it (it applies to law = \"interface\")";
      if (it.Dn != defaults.Dn) warn("Dn", stiffness_text(it.Dn), why);
      if (it.Dt != defaults.Dt) warn("Dt", stiffness_text(it.Dt), why);
      if (it.traction_law != defaults.traction_law)
        warn("traction_law", quoted_word(it.traction_law), why);
      if (it.Dn_compression != defaults.Dn_compression)
        warn("Dn_compression", stiffness_text(it.Dn_compression), why);
      if (it.force_limit != defaults.force_limit) warn("force_limit", "false", why);
      if (it.integration != defaults.integration)
        warn("integration", quoted_word(it.integration), why);
    } else if (it.traction_law == TractionLaw::linear &&
               it.Dn_compression != defaults.Dn_compression) {
      warn("Dn_compression", stiffness_text(it.Dn_compression),
           "traction_law = \"linear\" uses Dn in compression too (Dn_compression applies to "
           "traction_law = \"bilinear\")");
    }
    // Coulomb's coefficient (P-16) is read by law = "friction" only.
    if (it.law != Law::friction && it.friction != defaults.friction) {
      warn("friction", format_number(it.friction),
           law + " does not read it (it applies to law = \"friction\")");
    }
    const std::string normal = "normal = " + quoted_word(it.normal);
    if (it.normal != NormalMethod::specified && it.normal_vector != defaults.normal_vector) {
      warn("normal_vector", format_vector(it.normal_vector, dim),
           normal + " computes its own normal (normal_vector applies to normal = \"specified\")");
    }
    if (it.normal != NormalMethod::radial && it.center != defaults.center) {
      warn("center", format_vector(it.center, dim),
           normal + " does not read it (center applies to normal = \"radial\")");
    }
  }
  return out;
}

}  // namespace mmpm
