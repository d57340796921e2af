#pragma once
// Interpolation methods the frame pipeline offers. All of them are evaluated by the same kernel
// from element Bezier control points (docs/method.md fact 5); they differ only in the per-vertex
// matrices M: BI is M = 0 (no solve), modified-BI solves M from the control positions, Phong
// deformation takes M_i = F_i / 2 in closed form (interp/phong.hpp, no factorisation).
#include <mbi/base/names.hpp>

#include <optional>
#include <string_view>
#include <vector>

namespace mbi::pipeline {

enum class Method {
  BI,          ///< plain barycentric interpolation (M = 0): no precompute, no solve
  ModifiedBI,  ///< modified-BI (Huang et al. 2008): M minimises alpha E_vibr + beta E_disc
  Phong,       ///< Phong deformation (James 2020): M_i = F_i / 2, vertex deformation gradients
};

/// "bi", "modified-bi", "phong": the names used in scene files, on the command line and in
/// messages, in the order of menus and comparisons.
inline constexpr auto kMethodNames = name_table<Method>(
    {{Method::BI, "bi"}, {Method::ModifiedBI, "modified-bi"}, {Method::Phong, "phong"}});

/// kMethodNames' name of m.
const char* method_name(Method m);
/// Parses a name of method_name(); nullopt for anything else.
std::optional<Method> parse_method(std::string_view name);
/// Every method, in kMethodNames' order (for menus, comparisons and option checks).
const std::vector<Method>& all_methods();
/// The names of all_methods() joined by ", " (for error messages and --help).
const char* method_names();
/// True when the method's M comes from the modified-BI solve (and needs its precompute).
bool needs_solve(Method m);
/// True when the method's M comes from Phong's closed form (and needs its vertex weights).
bool needs_phong(Method m);

}  // namespace mbi::pipeline
