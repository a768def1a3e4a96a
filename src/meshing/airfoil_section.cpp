// The wing section of thesis section 6.3.3.2 (see airfoil_section.hpp).

#include "airfoil_section.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "gmsh_model.hpp"
#include "meshing_error.hpp"

namespace hom::meshing {

std::vector<Eigen::Vector2d> read_selig_airfoil(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the airfoil file");
  std::vector<Eigen::Vector2d> points;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ss(line);
    double x, y;
    if (!(ss >> x >> y)) {
      if (number == 1) continue;  // the name line
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected two numbers 'x y'");
    }
    points.emplace_back(x, y);
  }
  if (points.size() < 8) throw std::runtime_error(path + ": fewer than 8 airfoil points");
  return points;
}

std::vector<Eigen::Vector2d> naca_00xx(double thickness, int points_per_side) {
  if (!(thickness > 0) || points_per_side < 4) throw std::invalid_argument("naca_00xx: need thickness > 0, >= 4 points");
  // Half thickness of the NACA four-digit series, closed trailing edge.
  auto half = [thickness](double x) {
    return 5 * thickness *
           (0.2969 * std::sqrt(x) - 0.1260 * x - 0.3516 * x * x + 0.2843 * x * x * x - 0.1036 * x * x * x * x);
  };
  std::vector<Eigen::Vector2d> p;
  const int n = points_per_side - 1;
  for (int i = 0; i <= n; ++i) {  // upper: trailing edge -> leading edge
    const double x = 0.5 * (1 + std::cos(std::numbers::pi * i / n));
    p.emplace_back(x, half(x));
  }
  for (int i = n - 1; i >= 0; --i) {  // lower: leading edge -> trailing edge
    const double x = 0.5 * (1 + std::cos(std::numbers::pi * i / n));
    p.emplace_back(x, -half(x));
  }
  return p;
}

void write_airfoil_section_brep(const AirfoilSectionOptions& o, const std::string& path) {
  const auto& pr = o.profile;
  if (pr.size() < 8) throw std::invalid_argument("write_airfoil_section_brep: the profile needs at least 8 points");
  if (!(o.span > 0)) throw std::invalid_argument("write_airfoil_section_brep: span must be positive");
  for (const auto& q : pr)
    if (!(q.array() > o.lo.array()).all() || !(q.array() < o.hi.array()).all())
      throw std::invalid_argument("write_airfoil_section_brep: the profile is not inside the box");
  const auto le = std::min_element(pr.begin(), pr.end(), [](const auto& a, const auto& b) { return a[0] < b[0]; });
  const auto i_le = std::size_t(le - pr.begin());
  if (i_le < 2 || i_le + 3 > pr.size())
    throw std::invalid_argument("write_airfoil_section_brep: the leading edge must split the profile into two sides");
  double chord = 0;
  for (const auto& q : pr) chord = std::max(chord, (q - *le).norm());
  // Ends closer than this are one point (a sharp trailing edge written twice).
  const bool closed = (pr.front() - pr.back()).norm() < 1e-4 * chord;

  const GmshSession session({o.verbose, 1, "the airfoil section"});
  gmsh_call([&] {
    gmsh::model::add("hom_airfoil_section");
    namespace occ = gmsh::model::occ;
    auto point = [](const Eigen::Vector2d& q) { return occ::addPoint(q[0], q[1], 0.0); };
    std::vector<int> upper, lower;
    for (std::size_t i = 0; i <= i_le; ++i) upper.push_back(point(pr[i]));
    lower.push_back(upper.back());
    for (std::size_t i = i_le + 1; i + 1 < pr.size(); ++i) lower.push_back(point(pr[i]));
    lower.push_back(closed ? upper.front() : point(pr.back()));
    std::vector<int> loop = {occ::addSpline(upper), occ::addSpline(lower)};
    if (!closed) loop.push_back(occ::addLine(lower.back(), upper.front()));
    // The splines' interior points would stay in the model as free vertices
    // (and become fixed mesh nodes): only the curves' ends are kept.
    gmsh::vectorpair interior;
    for (std::size_t i = 1; i + 1 < upper.size(); ++i) interior.push_back({0, upper[i]});
    for (std::size_t i = 1; i + 1 < lower.size(); ++i) interior.push_back({0, lower[i]});
    occ::remove(interior);
    const int profile = occ::addCurveLoop(loop);
    const int c0 = occ::addPoint(o.lo[0], o.lo[1], 0), c1 = occ::addPoint(o.hi[0], o.lo[1], 0);
    const int c2 = occ::addPoint(o.hi[0], o.hi[1], 0), c3 = occ::addPoint(o.lo[0], o.hi[1], 0);
    const int outer = occ::addCurveLoop(
        {occ::addLine(c0, c1), occ::addLine(c1, c2), occ::addLine(c2, c3), occ::addLine(c3, c0)});
    const int face = occ::addPlaneSurface({outer, profile});
    gmsh::vectorpair out;
    occ::extrude({{2, face}}, 0, 0, o.span, out);
    occ::synchronize();
    gmsh::vectorpair volumes;
    gmsh::model::getEntities(volumes, 3);
    if (volumes.size() != 1) throw std::runtime_error("gmsh: the extruded section is not one volume");
    gmsh::write(path);
    gmsh::model::remove();
  });
}

}  // namespace hom::meshing
