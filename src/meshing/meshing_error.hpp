#pragma once
/// @file meshing_error.hpp
/// Runs Gmsh API calls and turns their failures into std::runtime_error
/// carrying Gmsh's last error message. Internal to src/meshing (includes
/// gmsh.h).

#include <gmsh.h>

#include <stdexcept>
#include <string>

namespace hom::meshing {

template <class F>
void gmsh_call(F&& f) {
  try {
    f();
  } catch (const std::exception&) {
    throw;
  } catch (...) {
    std::string last;
    try {
      gmsh::logger::getLastError(last);
    } catch (...) {
    }
    throw std::runtime_error("gmsh: " + (last.empty() ? std::string("API call failed") : last));
  }
}

}  // namespace hom::meshing
