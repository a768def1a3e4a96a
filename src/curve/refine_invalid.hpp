#pragma once
/// @file refine_invalid.hpp
/// What to do with a curved mesh that came out invalid (hom curve
/// --refine-invalid, bench_curve --refine-invalid): name the elements to blame
/// and put a ball of finer size around each, where the model is meshed again
/// (CadMeshOptions::local_sizes, Gmsh's Ball fields).
///
/// A linear element larger than a feature of the CAD it touches (a leading
/// edge, a fillet, a wing root's fairing) may admit no valid curved position
/// with its boundary nodes on the CAD, whatever its free nodes do; smaller
/// elements there can follow the feature. The thesis's meshes of section 6.3
/// are sized to their geometry beforehand; this sizes them after the fact,
/// only where the curving failed.

#include <algorithm>
#include <optional>
#include <utility>
#include <vector>

#include "cad_mesher.hpp"
#include "curve_mesh.hpp"

namespace hom::cad {

/// Why a curve_mesh result is invalid (the first reason that applies).
enum class Failure {
  none,               ///< valid
  faces_uncertified,  ///< CAD-face triangles not certified valid, the volume stage skipped (volume_skipped_for)
  inverted,           ///< det D phi <= 0 at a quadrature point of some element
  off_cad,            ///< a boundary node off its CAD entity: no element to blame
  uncertified,        ///< CurveOptions::certify: some element not certified valid
  folded_at_node,     ///< det D phi <= 0 at a node: a fold at an element corner that no quadrature point sees
};

struct FailingElements {
  Failure why = Failure::none;
  /// Every element that fails for any reason (inverted, not certified, folded
  /// at a node), ascending: a refinement around only the first reason's
  /// elements would leave the others for another try.
  std::vector<int> elements;
};

/// det D phi <= 0 at a node of element `e` (the result's scaled Jacobian there);
/// on a surface only < 0, since a surface's normal may vanish at a pole.
template <class MeshT>
bool folded_at_node(const CurveResult<MeshT>& r, int e) {
  const double sj = r.element_scaled_jacobian[e];
  return MeshT::space_dim == MeshT::dim ? !(sj > 0.0) : !(sj >= 0.0);
}

template <class MeshT>
int count_folded_at_nodes(const CurveResult<MeshT>& r) {
  int n = 0;
  for (int e = 0; e < int(r.element_scaled_jacobian.size()); ++e) n += folded_at_node(r, e);
  return n;
}

/// The elements that make `r` invalid, and why (the first reason that
/// applies). A result whose volume stage was skipped blames only the elements
/// on the uncertified CAD faces: its other elements are the initial curved
/// volume's, which the volume stage would have untangled.
template <class MeshT>
FailingElements failing_elements(const CurveResult<MeshT>& r) {
  FailingElements f;
  if (!r.volume_skipped_for.empty()) return {Failure::faces_uncertified, r.volume_skipped_for};
  const bool uncertified = r.certification && !r.certification->certified();
  const int folded = count_folded_at_nodes(r);
  if (r.valid && !uncertified && folded == 0) return f;
  f.why = r.inverted > 0         ? Failure::inverted
          : !r.conformity.ok     ? Failure::off_cad
          : uncertified          ? Failure::uncertified
                                 : Failure::folded_at_node;
  std::vector<bool> failing(std::size_t(r.mesh.num_elements()), false);
  if (uncertified)
    for (int e : r.certification->uncertified) failing[std::size_t(e)] = true;
  for (int e = 0; e < r.mesh.num_elements(); ++e) {
    const bool inverted = r.inverted > 0 && !r.element_valid[e];
    if (failing[std::size_t(e)] || inverted || folded_at_node(r, e)) f.elements.push_back(e);
  }
  return f;
}

/// A ball around each of `elements`: centred at its centroid, as wide as the
/// element (the largest distance between two of its nodes), the size inside
/// half that width.
template <class MeshT>
std::vector<LocalSize> balls_around(const MeshT& mesh, const std::vector<int>& elements) {
  std::vector<LocalSize> balls;
  for (int e : elements) {
    const auto x = mesh.element_coordinates(e);
    double width = 0.0;
    for (int i = 0; i < int(x.cols()); ++i)
      for (int j = i + 1; j < int(x.cols()); ++j) width = std::max(width, (x.col(i) - x.col(j)).norm());
    LocalSize ball;
    ball.center.head(x.rows()) = x.rowwise().mean();
    ball.radius = width;
    ball.size = width / 2;
    balls.push_back(ball);
  }
  return balls;
}

/// Adds `balls` to `options` for the next mesh of the model. A ball centred
/// in one of the options' earlier balls, where the model failed again at that
/// ball's size, gets at most half that size, so that each try is finer there
/// than the last whatever the failing elements' widths. When they ask
/// for less than size_min with curvature sizing on (balls_lower_curvature_floor),
/// `earlier`'s sizes are kept outside the balls (CadMeshOptions::earlier_sizes;
/// the first such mesh's, since later ones hold the balls' sizes) rather than
/// Gmsh's floor lowered for the whole model: on wing_fuselage.step at p = 2
/// the lowered floor took four meshes to 11297 tetrahedra, these sizes three
/// to 4411. Returns whether earlier sizes are in use.
template <class MeshT>
bool refine_around(CadMeshOptions& options, std::vector<LocalSize>& balls, const MeshT& earlier) {
  for (auto& ball : balls)
    for (const auto& before : options.local_sizes)
      if ((ball.center - before.center).norm() < before.radius) ball.size = std::min(ball.size, before.size / 2);
  options.local_sizes.insert(options.local_sizes.end(), balls.begin(), balls.end());
  if (options.earlier_sizes.empty() && balls_lower_curvature_floor(options))
    options.earlier_sizes = size_map(earlier);
  return !options.earlier_sizes.empty();
}

/// What the next try of curve_refining_invalid meshes with: `options` with
/// the new balls (refine_around), the size floor before them, and whether
/// the first mesh's sizes are kept outside them.
struct Refinement {
  const CadMeshOptions& options;
  const std::vector<LocalSize>& balls;
  double floor_before = 0.0;
  bool kept_sizes = false;
  int next_try = 2;  ///< 1: the first mesh
};

/// The tries of --refine-invalid N (hom curve, bench_curve): `curve(linear,
/// last)` curves the linear mesh and returns balls around its failing
/// elements (balls_around; none where the result stands); the model is then
/// meshed again finer in them by `remesh(refinement)`, which returns the new
/// linear mesh, or nothing where the meshing failed (the result then stands
/// at the last curved try's). A try with tries after it (`last` false) may
/// skip its volume stage when its CAD faces are left uncertified: the next
/// try mends a face sooner (CurveOptions::skip_volume_if_faces_uncertified).
/// At most 1 + extra_tries tries; returns how many were made.
template <class Linear, class Curve, class Remesh>
int curve_refining_invalid(CadMeshOptions& options, Linear& linear, int extra_tries, Curve curve, Remesh remesh) {
  for (int tries = 1;; ++tries) {
    const bool last = tries > extra_tries;
    auto balls = curve(static_cast<const Linear&>(linear), last);
    if (last || balls.empty()) return tries;
    const double floor = size_floor(options);  // before the new balls
    const bool kept_sizes = refine_around(options, balls, linear);
    std::optional<Linear> next = remesh(Refinement{options, balls, floor, kept_sizes, tries + 1});
    if (!next) return tries;
    linear = std::move(*next);
  }
}

}  // namespace hom::cad
