// The simplifier options pmz-encode and pmz-simplify share: how attributes steer the engine.
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "pmz/simplify.hpp"

namespace pmz::tool {

// --attributes geometry-only|seams|full (default full) and --attribute-weight W.
inline void add_attribute_options(CLI::App& app, std::string& mode, float& weight) {
  app.add_option("--attributes", mode,
                 "how texture coordinates, normals, colours and materials steer the "
                 "simplification (spec/algorithm.md section 7): full: seams and material "
                 "boundaries kept as discontinuity curves, attribute error added to the cost; "
                 "seams: the curves only; geometry-only: ignored (the geometric metric alone). A "
                 "mesh without attributes simplifies the same in every mode")
      ->check(CLI::IsMember({"full", "seams", "geometry-only"}))
      ->capture_default_str();
  app.add_option("--attribute-weight", weight,
                 "full: weight of the attribute error against the geometric cost")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

inline AttributeMode attribute_mode(const std::string& name) {
  return name == "geometry-only" ? AttributeMode::geometry_only
         : name == "seams"       ? AttributeMode::seams
                                 : AttributeMode::full;
}

}  // namespace pmz::tool
