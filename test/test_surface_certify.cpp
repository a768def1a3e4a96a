// Certification and repair of surface meshes (include/hom/surface/
// certified_surface.hpp, issues 6 and 8):
//   - on the plane z = 0 a surface element's certificate is the planar
//     element's (g = (x_xi x x_eta) . e_z is the planar det);
//   - a degree-3 patch on a sphere whose boundary edge is bent into an
//     element folds it at a corner; optimized on the sphere it is valid at
//     every quadrature point but certified invalid, and the repair rounds
//     make it certified valid. The fold and its repair are checked
//     independently of the Bernstein certificate, through the Lagrange
//     Jacobian of the element's map in R^3 against the surface normal; the
//     nodes stay on the sphere, held nodes stay put and only nodes near the
//     fold move;
//   - a patch that certifies valid is left bitwise unchanged; with no repair
//     rounds the stage reports and names the folded elements.
#include <doctest/doctest.h>

#include <cmath>
#include <set>
#include <vector>

#include <Eigen/Dense>

#include "hom/basis/lagrange.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quality/certify.hpp"
#include "hom/surface/certified_surface.hpp"
#include "hom/surface/optimize_surface.hpp"

using namespace hom;

namespace {

using F = Simplex<2>;
using N = WarpBlend;
using UVs = Eigen::Matrix2Xd;
using SurfaceMesh = Mesh<F, N, 3>;

constexpr int cells = 3;
constexpr double lo = -0.6, hi = 0.6;

Mesh<F, N> parameter_mesh(int p) {
  return elevate(structured_mesh<F, N>({cells, cells}, Eigen::Vector2d::Constant(lo), Eigen::Vector2d::Constant(hi)), p);
}

template <class G>
Eigen::Matrix3Xd on_surface(const G& g, const UVs& uv) {
  Eigen::Matrix3Xd X(3, uv.cols());
  for (Eigen::Index i = 0; i < uv.cols(); ++i) X.col(i) = g.evaluate(uv.col(i));
  return X;
}

/// (x_xi x x_eta) . n(xi) of element e at reference point xi through the
/// Lagrange basis, n the interpolated unit surface normals of its nodes
/// (the sign the optimizer tests and the certificate bounds).
template <class G>
double normal_det(const SurfaceMesh& mesh, const G& g, const UVs& uv, int e, const F::Point& xi) {
  const Eigen::Matrix3Xd X = mesh.element_coordinates(e);
  const auto& basis = lagrange_basis<F, N>(mesh.degree());
  const Eigen::Matrix<double, 3, 2> J = X * basis.gradient(xi);
  Eigen::Matrix2Xd UV(2, mesh.nodes_per_element());
  for (int i = 0; i < mesh.nodes_per_element(); ++i) UV.col(i) = uv.col(mesh.elements()(i, e));
  return J.col(0).cross(J.col(1)).dot(element_unit_normals(g, UV) * basis.value(xi));
}

/// The degree-p patch of the sphere over [lo, hi]^2 in (u, v), with the
/// boundary node of v = lo nearest to u = lo + h + h / (2p) moved by
/// (-shift, +height) h in (u, v) (h the cell size): its boundary edge bends
/// into the element at the edge's end vertex. The ideal is the unmoved
/// patch's straight-sided elements.
struct FoldedPatch {
  SurfaceMesh mesh;
  UVs uv;
};
template <class G>
FoldedPatch folded_patch(const G& g, int p, double shift, double height) {
  const auto param = parameter_mesh(p);
  FoldedPatch out{SurfaceMesh(p, on_surface(g, param.nodes()), param.elements()), param.nodes()};
  out.mesh.reset_ideal();
  const double h = (hi - lo) / cells;
  const Eigen::Vector2d target(lo + h + 0.5 * h / p, lo);
  int best = -1;
  for (int i = 0; i < out.uv.cols(); ++i)
    if (std::abs(out.uv(1, i) - lo) < 1e-12 && (best < 0 || (out.uv.col(i) - target).norm() < (out.uv.col(best) - target).norm()))
      best = i;
  REQUIRE(best >= 0);
  out.uv.col(best) += h * Eigen::Vector2d(-shift, height);
  out.mesh.nodes() = on_surface(g, out.uv);
  return out;
}

CertifyRepairOptions repair_options(int rounds) {
  CertifyRepairOptions o;
  o.max_rounds = rounds;
  return o;
}

}  // namespace

TEST_CASE("surface certify: on the plane z = 0 an element's certificate is the planar element's") {
  const Plane plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX());
  const int p = 3;
  int invalid = 0;
  for (double height : {0.0, 0.4, 0.8}) {
    const auto patch = folded_patch(plane, p, 0.6, height);
    for (int e = 0; e < patch.mesh.num_elements(); ++e) {
      Eigen::Matrix2Xd X2 = patch.mesh.element_coordinates(e).topRows<2>();
      const Eigen::Matrix3Xd up = Eigen::Vector3d::UnitZ().replicate(1, patch.mesh.nodes_per_element());
      const auto a = certify_surface_element<F, N>(p, patch.mesh.element_coordinates(e), up, CertifyOptions{});
      const auto b = certify_element<F>(jacobian_bernstein<F, N>(p), X2, CertifyOptions{});
      CHECK(a.status == b.status);
      // The same polynomial in a space of higher degree (3p - 2 against 2p - 2):
      // its coefficients bound det at least as tightly.
      if (a.depth == 0 && b.depth == 0) CHECK(a.min_det_bound >= b.min_det_bound - 1e-12 * std::abs(b.min_det_bound));
      invalid += a.status == Certificate::certified_invalid;
    }
  }
  CHECK(invalid > 0);  // the bent boundary folds elements in the plane too
}

TEST_CASE("surface certify: a corner fold on a sphere that the surface optimizer leaves is repaired until certified") {
  const Sphere sphere(Eigen::Vector3d::Zero(), 2.0);
  const int p = 3;
  int folds = 0, repaired = 0;
  for (double shift : {0.3, 0.6})
    for (double height : {0.2, 0.4, 0.6, 0.8}) {
      CAPTURE(shift);
      CAPTURE(height);
      auto patch = folded_patch(sphere, p, shift, height);
      OptimizeOptions oo;
      oo.threads = 1;
      oo.ideal = IdealKind::straight_sided;
      const auto ideals = surface_ideals(patch.mesh, oo.ideal);
      const auto r0 = optimize_surface(patch.mesh, sphere, patch.uv, ideals, oo);
      // The premise: valid at the quadrature points, certified invalid, and
      // the Lagrange Jacobian confirms det <= 0 at the certificate's point.
      if (r0.inverted() > 0) continue;
      const auto before = certify_surface_elements(patch.mesh, sphere, patch.uv, CertifyOptions{});
      std::vector<int> failing;
      for (int e = 0; e < patch.mesh.num_elements(); ++e)
        if (before[e].status == Certificate::certified_invalid) {
          failing.push_back(e);
          REQUIRE(before[e].invalid_point.has_value());
          CHECK(normal_det(patch.mesh, sphere, patch.uv, e, *before[e].invalid_point) <= 1e-12);
        }
      if (failing.empty()) continue;
      ++folds;

      const SurfaceMesh plain = patch.mesh;
      const UVs plain_uv = patch.uv;
      const auto free = surface_free_node_mask(patch.mesh);
      const auto c = certify_and_repair_surface(patch.mesh, sphere, patch.uv, ideals, oo.solver_options(),
                                                repair_options(4), 1);
      CHECK(c.on_surface);
      CHECK(c.initial_invalid == int(failing.size()));
      CHECK(c.valid + c.invalid + c.undecided == patch.mesh.num_elements());
      CHECK(int(c.repairs.size()) == c.rounds);
      // The outcome is the certificate of the result.
      const auto after = certify_surface_elements(patch.mesh, sphere, patch.uv, CertifyOptions{});
      std::vector<int> uncertified;
      for (int e = 0; e < patch.mesh.num_elements(); ++e)
        if (after[e].status != Certificate::certified_valid) uncertified.push_back(e);
      CHECK(c.uncertified == uncertified);
      // On the sphere; held nodes stay.
      for (int i = 0; i < patch.mesh.num_nodes(); ++i) {
        CHECK((patch.mesh.node(i) - sphere.evaluate(patch.uv.col(i))).norm() <= 1e-14);
        if (!free[i]) CHECK(patch.uv.col(i) == plain_uv.col(i));
      }
      if (!c.certified()) {
        MESSAGE("shift " << shift << " height " << height << ": " << to_string(c.reason) << ", rounds " << c.rounds
                         << ", pull-backs " << c.pull_backs << ", " << c.initial_invalid << " -> " << c.invalid << " invalid, "
                         << c.undecided << " undecided, restored " << c.restored);
        CHECK(c.reason != RepairStop::certified);
        CHECK((c.invalid + c.undecided < int(failing.size()) || patch.uv == plain_uv));
        continue;
      }
      ++repaired;
      CHECK(c.reason == RepairStop::certified);
      CHECK_FALSE(c.restored);
      CHECK(c.rounds >= 1);
      // Still valid at the quadrature points.
      const MeshQuality q = surface_mesh_quality(patch.mesh, sphere, patch.uv, ShapeMeasure{}, IdealKind::straight_sided,
                                                 quadrature_for<F, DefaultExactness>(p));
      for (const auto& e : q.elements) CHECK(e.valid);
      // Independently: det > 0 at the old failing points and at every vertex.
      for (int e : failing) {
        CHECK(normal_det(patch.mesh, sphere, patch.uv, e, *before[e].invalid_point) > 0.0);
        for (int v = 0; v < F::num_vertices; ++v) CHECK(normal_det(patch.mesh, sphere, patch.uv, e, F::vertex(v)) > 0.0);
      }
      // Local: with one round, only nodes of elements within the round's
      // rings of the failing elements move.
      if (c.rounds == 1) {
        std::set<int> near;
        for (int e : failing)
          for (int i = 0; i < plain.nodes_per_element(); ++i) near.insert(plain.elements()(i, e));
        for (int ring = 0; ring < (c.pull_backs > 0 ? CertifyRepairOptions{}.pull_back_rings : 1); ++ring) {
          std::set<int> grown = near;
          for (int e = 0; e < plain.num_elements(); ++e) {
            bool touches = false;
            for (int i = 0; i < plain.nodes_per_element(); ++i) touches = touches || near.count(plain.elements()(i, e));
            if (touches)
              for (int i = 0; i < plain.nodes_per_element(); ++i) grown.insert(plain.elements()(i, e));
          }
          near = std::move(grown);
        }
        int moved = 0;
        for (int i = 0; i < plain.num_nodes(); ++i)
          if (patch.uv.col(i) != plain_uv.col(i)) {
            ++moved;
            CHECK(near.count(i) == 1);
          }
        CHECK(moved > 0);
      }
    }
  CHECK(folds >= 3);  // the construction produced the case under test
  // 5 of 8 with the interpolated nodal normals (measured; 6 with 12 rounds).
  // With one mean normal per element the certificate could disagree in sign
  // with the optimizer at a nearly degenerate corner, and only 2 were repaired.
  CHECK(repaired >= 4);
  MESSAGE(repaired << " of " << folds << " surface folds repaired");
}

TEST_CASE("surface certify: a patch that certifies valid is left bitwise unchanged") {
  const Sphere sphere(Eigen::Vector3d::Zero(), 2.0);
  auto patch = folded_patch(sphere, 3, 0.0, 0.0);
  const SurfaceMesh mesh0 = patch.mesh;
  const UVs uv0 = patch.uv;
  const auto c = certify_and_repair_surface(patch.mesh, sphere, patch.uv, surface_ideals(patch.mesh, IdealKind::straight_sided),
                                            SolverOptions{}, repair_options(4), 1);
  CHECK(c.certified());
  CHECK(c.reason == RepairStop::certified);
  CHECK(c.rounds == 0);
  CHECK(c.valid == patch.mesh.num_elements());
  CHECK(c.uncertified.empty());
  CHECK(patch.uv == uv0);
  CHECK(patch.mesh.nodes() == mesh0.nodes());
}

TEST_CASE("surface certify: with no repair rounds the stage reports and names the folded elements") {
  const Sphere sphere(Eigen::Vector3d::Zero(), 2.0);
  auto patch = folded_patch(sphere, 3, 0.6, 0.8);
  const UVs uv0 = patch.uv;
  const auto before = certify_surface_elements(patch.mesh, sphere, patch.uv, CertifyOptions{});
  std::vector<int> failing;
  for (int e = 0; e < patch.mesh.num_elements(); ++e)
    if (before[e].status != Certificate::certified_valid) failing.push_back(e);
  REQUIRE_FALSE(failing.empty());
  const auto c = certify_and_repair_surface(patch.mesh, sphere, patch.uv, surface_ideals(patch.mesh, IdealKind::straight_sided),
                                            SolverOptions{}, repair_options(0), 1);
  CHECK_FALSE(c.certified());
  CHECK(c.reason == RepairStop::round_limit);
  CHECK(c.rounds == 0);
  CHECK(c.uncertified == failing);
  CHECK(patch.uv == uv0);
}
