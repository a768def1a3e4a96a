// Boundary-layer insertion (include/hom/mesh/boundary_layer.hpp): on
// structured simplex meshes of the unit square / cube with one or two sides
// as wall, the inserted mesh is conformal, positively oriented, fills the same
// domain with the same boundary (the wall refined), has the template element
// counts, and its ideal layer elements have the prescribed heights.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>
#include <vector>

#include "hom/mesh/boundary_layer.hpp"
#include "hom/mesh/elevate.hpp"
#include "hom/mesh/layer_count.hpp"
#include "hom/geometry/circle.hpp"
#include "hom/geometry/cylinder.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/optimize/boundary_layer_pipeline.hpp"
#include "hom/quality/certify.hpp"
#include "hom/mesh/structured.hpp"
#include "hom/mesh/topology.hpp"

namespace {

template <int Dim>
using SimplexMesh = hom::Mesh<hom::Simplex<Dim>>;

template <int Dim>
double factorial() {
  return Dim == 2 ? 2.0 : 6.0;
}

template <int Dim>
double signed_volume(const Eigen::Matrix<double, Dim, Dim + 1>& v) {
  Eigen::Matrix<double, Dim, Dim> J;
  for (int k = 0; k < Dim; ++k) J.col(k) = v.col(k + 1) - v.col(0);
  return J.determinant() / factorial<Dim>();
}

template <int Dim>
Eigen::Matrix<double, Dim, Dim + 1> vertices(const SimplexMesh<Dim>& m, int e) {
  Eigen::Matrix<double, Dim, Dim + 1> v;
  for (int k = 0; k <= Dim; ++k) v.col(k) = m.node(m.vertex(e, k));
  return v;
}

template <int Dim>
double facet_measure(const SimplexMesh<Dim>& m, const std::array<int, Dim>& f) {
  if constexpr (Dim == 2)
    return (m.node(f[1]) - m.node(f[0])).norm();
  else
    return 0.5 * (m.node(f[1]) - m.node(f[0])).cross(m.node(f[2]) - m.node(f[0])).norm();
}

/// Total measure of the classified boundary facets per entity tag.
template <int Dim>
std::map<int, double> boundary_measure(const SimplexMesh<Dim>& m) {
  std::map<int, double> out;
  for (const auto& f : m.boundary_facets()) out[f.entity_tag] += facet_measure<Dim>(m, f.vertices);
  return out;
}

template <int Dim>
int count_tag(const SimplexMesh<Dim>& m, int tag) {
  int n = 0;
  for (const auto& f : m.boundary_facets()) n += f.entity_tag == tag;
  return n;
}

/// Tag of the box side x_axis = lo (structured.hpp's tag rule).
template <int Dim>
int side_tag(int axis) {
  hom::detail::BoxState<Dim> s{};
  s.fill(2);
  s[axis] = 0;
  return hom::detail::box_entity_tag<Dim>(s);
}

template <int Dim>
SimplexMesh<Dim> box(int n) {
  std::array<int, Dim> cells{};
  cells.fill(n);
  return hom::structured_mesh<hom::Simplex<Dim>>(cells);
}

/// The properties every insertion must have (file comment).
template <int Dim>
void check_insertion(const SimplexMesh<Dim>& in, const std::vector<int>& walls, const hom::BoundaryLayerOptions& o) {
  const auto bl = hom::insert_boundary_layer(in, walls, o);
  const auto& m = bl.mesh;
  int T = 0;
  for (int w : walls) T += count_tag<Dim>(in, w);
  const int per_facet = Dim == 3 ? 12 * (o.layers - 1) + 7 : 4 * (o.layers - 1) + 3;
  CHECK(bl.num_wall_facets == T);
  CHECK(bl.num_original_elements == in.num_elements());
  CHECK(m.num_elements() == in.num_elements() + T * per_facet);
  REQUIRE(bl.ideal.size() == m.num_elements());
  REQUIRE(int(bl.level.size()) == m.num_elements());

  // Positive volumes, same total volume.
  double volume = 0.0, min_volume = 1e300;
  for (int e = 0; e < m.num_elements(); ++e) {
    const double v = signed_volume<Dim>(vertices<Dim>(m, e));
    volume += v;
    min_volume = std::min(min_volume, v);
  }
  CHECK(min_volume > 0.0);
  CHECK(volume == doctest::Approx(1.0).epsilon(1e-12));

  // Conformal: Topology accepts it (no facet of three elements), the facets
  // with one element are exactly the classified boundary, which covers each
  // side with the same measure as before, and the complex is still a ball.
  const hom::Topology<hom::Simplex<Dim>> topo(m);
  CHECK(topo.euler_characteristic() == hom::Topology<hom::Simplex<Dim>>(in).euler_characteristic());
  std::set<std::array<int, Dim>> classified;
  for (const auto& f : m.boundary_facets()) {
    auto k = f.vertices;
    std::sort(k.begin(), k.end());
    classified.insert(k);
  }
  CHECK(classified.size() == m.boundary_facets().size());
  CHECK(topo.boundary_facets().size() == m.boundary_facets().size());
  for (const auto& r : topo.boundary_facets()) {
    std::array<int, Dim> k{};
    const auto lv = hom::facet_vertices<hom::Simplex<Dim>>(r.local);
    for (int i = 0; i < Dim; ++i) k[i] = m.vertex(r.element, lv[i]);
    std::sort(k.begin(), k.end());
    CHECK(classified.count(k) == 1);
  }
  const auto before = boundary_measure<Dim>(in), after = boundary_measure<Dim>(m);
  REQUIRE(before.size() == after.size());
  for (const auto& [tag, measure] : before) CHECK(after.at(tag) == doctest::Approx(measure).epsilon(1e-12));
  for (int w : walls) CHECK(count_tag<Dim>(m, w) == (Dim == 3 ? 4 : 2) * count_tag<Dim>(in, w));
  // A classified facet names its element's local facet.
  for (const auto& f : m.boundary_facets()) {
    const auto lv = hom::facet_vertices<hom::Simplex<Dim>>(f.local_facet);
    std::set<int> a(f.vertices.begin(), f.vertices.end()), b;
    for (int l : lv) b.insert(m.vertex(f.element, l));
    CHECK(a == b);
  }

  // Wall nodes stay where the wall was: on a side x_axis = 0.
  for (int n : bl.wall_nodes) {
    bool on_some_wall = false;
    for (int a = 0; a < Dim; ++a) on_some_wall = on_some_wall || std::abs(m.node(n)[a]) < 1e-15;
    CHECK(on_some_wall);
  }

  // Ideals: original elements keep their input vertices; layer elements of
  // level k span exactly [H_k, H_{k+1}] along the wall normal (single wall:
  // the first listed axis) and are positive.
  double max_ar = 0.0;
  for (int e = 0; e < m.num_elements(); ++e) {
    const auto& I = bl.ideal.vertices(e);
    CHECK(signed_volume<Dim>(I) > 0.0);
    if (!bl.is_layer(e)) {
      REQUIRE(e < in.num_elements());
      CHECK((I - vertices<Dim>(in, e)).norm() == 0.0);
      continue;
    }
    CHECK(e >= in.num_elements());
    max_ar = std::max(max_ar, hom::simplex_aspect_ratio<Dim>(I));
    if (walls.size() != 1) continue;
    int axis = 0;
    for (int a = 0; a < Dim; ++a)
      if (side_tag<Dim>(a) == walls[0]) axis = a;
    const int k = *bl.level[e];
    const double lo = I.row(axis).minCoeff(), hi = I.row(axis).maxCoeff();
    CHECK(lo == doctest::Approx(o.cumulative_height(k)).epsilon(1e-12));
    CHECK(hi - lo == doctest::Approx(o.level_height(k)).epsilon(1e-10));
  }
  CHECK(bl.max_aspect_ratio == doctest::Approx(max_ar));
  CHECK(bl.total_height == doctest::Approx(o.total_height()));
}

}  // namespace

TEST_CASE_TEMPLATE("boundary layer: conformal, valid, same domain, prescribed heights", Dim, std::integral_constant<int, 2>,
                   std::integral_constant<int, 3>) {
  constexpr int D = Dim::value;
  const auto in = box<D>(D == 2 ? 3 : 2);
  for (int layers : {1, 2, 4})
    for (double growth : {1.0, 2.0}) {
      CAPTURE(layers);
      CAPTURE(growth);
      hom::BoundaryLayerOptions o{.first_height = 0.01, .growth = growth, .layers = layers};
      check_insertion<D>(in, {side_tag<D>(D - 1)}, o);  // the side x_last = 0
      check_insertion<D>(in, {side_tag<D>(0)}, o);      // x_0 = 0
      // Two walls meeting at a right angle share the layer along their edge.
      check_insertion<D>(in, {side_tag<D>(0), side_tag<D>(1)}, o);
    }
}

TEST_CASE_TEMPLATE("boundary layer: the thinner the first level, the larger the aspect ratio", Dim,
                   std::integral_constant<int, 2>, std::integral_constant<int, 3>) {
  constexpr int D = Dim::value;
  const auto in = box<D>(2);
  double previous = 0.0;
  for (double h : {1e-2, 1e-3, 1e-4}) {
    hom::BoundaryLayerOptions o{.first_height = h, .growth = 2.0, .layers = 3};
    const auto bl = hom::insert_boundary_layer(in, {side_tag<D>(0)}, o);
    // A level-0 element has height h and an edge of at least a quarter of a
    // cell side (the wall facets are halved or quartered).
    CHECK(bl.max_aspect_ratio >= 0.25 / h);
    CHECK(bl.max_aspect_ratio > previous);
    previous = bl.max_aspect_ratio;
  }
}

TEST_CASE("boundary layer: the number of layers that reach a total height") {
  // Whole levels: 1 + 2 + 4 = 7 is three layers, a little more is four.
  CHECK(hom::layers_for_total_height(1.0, 2.0, 7.0) == 3);
  CHECK(hom::layers_for_total_height(1.0, 2.0, 7.0 + 1e-9) == 4);
  CHECK(hom::layers_for_total_height(1.0, 2.0, 0.5) == 1);
  CHECK(hom::layers_for_total_height(0.5, 1.0, 2.0) == 4);  // no growth
  CHECK(hom::layers_for_total_height(1e-3, 2.0, 0.015) == 4);  // the README's example
  // Against BoundaryLayerOptions' own heights: the fewest layers whose top
  // reaches the total.
  for (double h0 : {1e-6, 2e-4, 0.01})
    for (double g : {1.0, 1.2, 2.0, 3.7})
      for (double total : {0.03, 0.1, 0.7}) {
        CAPTURE(h0);
        CAPTURE(g);
        CAPTURE(total);
        if (g == 1.0 && total / h0 > 1000) continue;  // beyond max_layers, checked below
        const int n = hom::layers_for_total_height(h0, g, total);
        const hom::BoundaryLayerOptions reached{.first_height = h0, .growth = g, .layers = n};
        CHECK(reached.total_height() >= total * (1.0 - 1e-12));
        CHECK(reached.cumulative_height(n - 1) < total);
      }
  CHECK_THROWS_AS(hom::layers_for_total_height(1e-6, 1.0, 1.0), std::invalid_argument);  // 10^6 layers
  CHECK_THROWS_AS(hom::layers_for_total_height(0.0, 2.0, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(hom::layers_for_total_height(1.0, 0.5, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(hom::layers_for_total_height(1.0, 2.0, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(hom::layers_for_total_height(1.0, 2.0, std::nan("")), std::invalid_argument);
}

TEST_CASE("boundary layer: aspect ratio of regular simplices and invariance") {
  const auto tri = hom::regular_ideal_vertices<hom::Simplex<2>>();
  const auto tet = hom::regular_ideal_vertices<hom::Simplex<3>>();
  CHECK(hom::simplex_aspect_ratio<2>(tri) == doctest::Approx(2.0 / std::sqrt(3.0)));
  CHECK(hom::simplex_aspect_ratio<3>(tet) == doctest::Approx(std::sqrt(1.5)));
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Matrix<double, 3, 4> v;
  v << 0, 1, 0.3, 0.2, 0, 0, 1, 0.4, 0, 0, 0, 0.05;
  const Eigen::Matrix<double, 3, 4> w = (3.0 * R * v).colwise() + Eigen::Vector3d(1, -2, 5);
  CHECK(hom::simplex_aspect_ratio<3>(w) == doctest::Approx(hom::simplex_aspect_ratio<3>(v)));
  Eigen::Matrix<double, 3, 4> flat = v;
  flat.row(2).setZero();
  CHECK(std::isinf(hom::simplex_aspect_ratio<3>(flat)));
}

TEST_CASE("boundary layer: bad input throws") {
  const auto in = box<3>(1);
  const int wall = side_tag<3>(2);
  auto insert = [&](hom::BoundaryLayerOptions o) { return hom::insert_boundary_layer(in, {wall}, o); };
  CHECK_THROWS_AS(insert({.first_height = 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(insert({.first_height = -1.0}), std::invalid_argument);
  CHECK_THROWS_AS(insert({.first_height = 0.1, .growth = 0.5}), std::invalid_argument);
  CHECK_THROWS_AS(insert({.first_height = 0.1, .layers = 0}), std::invalid_argument);
  CHECK_THROWS_AS(insert({.first_height = 0.1, .extrusion_fraction = 0.0}), std::invalid_argument);
  CHECK_THROWS_WITH_AS(insert({.first_height = 0.1, .growth = 0.5}), doctest::Contains("growth"), std::invalid_argument);
  CHECK_THROWS_AS(hom::insert_boundary_layer(in, {999}, {.first_height = 0.1}), std::invalid_argument);
  CHECK_THROWS_AS(hom::insert_boundary_layer(in, {}, {.first_height = 0.1}), std::invalid_argument);
  CHECK_THROWS_AS(hom::insert_boundary_layer(hom::elevate(in, 2), {wall}, {.first_height = 0.1}), std::invalid_argument);
  CHECK_NOTHROW(insert({.first_height = 0.1, .growth = 1.0, .layers = 1}));
}

TEST_CASE("boundary layer: classification of the new nodes") {
  const auto in = box<3>(2);
  const int wall = side_tag<3>(2);
  const auto bl = hom::insert_boundary_layer(in, {wall}, {.first_height = 0.01, .layers = 3});
  const auto& m = bl.mesh;
  // Wall copies keep the original's class; the moved originals are free
  // inside and stay on the side planes on the border.
  for (int n : bl.wall_nodes) {
    const auto& c = m.node_class(n);
    CHECK(c.kind != hom::NodeKind::free);
  }
  for (int n : bl.moved_nodes) {
    const auto x = m.node(n);
    const bool border = x[0] == 0.0 || x[0] == 1.0 || x[1] == 0.0 || x[1] == 1.0;
    CHECK((m.node_class(n).kind == hom::NodeKind::free) == !border);
    CHECK(x[2] == doctest::Approx(0.1 * bl.total_height));
    CHECK(bl.full_height_positions(2, n) == doctest::Approx(bl.total_height));
    CHECK(std::count(bl.border_nodes.begin(), bl.border_nodes.end(), n) == (border ? 1 : 0));
  }
  // The original elements' nodes off the wall are untouched.
  for (int n = 0; n < in.num_nodes(); ++n)
    if (std::find(bl.moved_nodes.begin(), bl.moved_nodes.end(), n) == bl.moved_nodes.end())
      CHECK((m.node(n) - in.node(n)).norm() == 0.0);
}

// --- the pipeline (include/hom/optimize/boundary_layer_pipeline.hpp) --------

namespace {

/// Quarter annulus 0.5 <= r <= 1.5, 0 <= theta <= pi / 2 of triangles: the
/// structured (r, theta) box mapped to Cartesian coordinates (det = r > 0
/// keeps the orientation); the inner circle (side r = lo) is the wall.
SimplexMesh<2> quarter_annulus(int nr, int nt) {
  auto m = hom::structured_mesh<hom::Simplex<2>>({nr, nt}, Eigen::Vector2d(0.5, 0.0),
                                                 Eigen::Vector2d(1.5, std::numbers::pi / 2));
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Eigen::Vector2d q = m.node(i);
    m.node(i) = Eigen::Vector2d(q[0] * std::cos(q[1]), q[0] * std::sin(q[1]));
  }
  m.reset_ideal();
  return m;
}

template <int Dim>
void check_pipeline(const hom::BoundaryLayerPipelineResult<Dim>& r, const SimplexMesh<Dim>& in,
                    const hom::BoundaryLayerPipelineOptions& o, bool expect_valid = true) {
  REQUIRE(r.stages.size() == 5);
  const char* names[] = {"inviscid", "inserted", "smoothed", "curved", "optimized"};
  const int per_facet = Dim == 3 ? 12 * (o.layer.layers - 1) + 7 : 4 * (o.layer.layers - 1) + 3;
  for (int s = 0; s < 5; ++s) {
    CAPTURE(s);
    CHECK(r.stages[s].name == names[s]);
    CHECK(r.stages[s].elements == (s == 0 ? in.num_elements() : in.num_elements() + r.layer.num_wall_facets * per_facet));
    CHECK(r.stages[s].p == (s < 3 ? 1 : o.p));
  }
  // The inviscid mesh is its own ideal.
  CHECK(r.stages[0].quality.min == doctest::Approx(1.0));
  CHECK(r.stages[0].quality.inverted == 0);
  // Smoothing against the stretched ideal improves the inserted topology,
  // and the result is valid.
  CHECK(r.stages[2].quality.inverted == 0);
  CHECK(r.stages[2].quality.min > r.stages[1].quality.min);
  CHECK(r.stages[2].quality.mean > r.stages[1].quality.mean);
  CHECK(r.stages[4].quality.inverted == 0);
  CHECK(r.stages[4].quality.min > 0.0);
  CHECK(r.stages[4].quality.min >= r.stages[3].quality.min - 1e-12);
  CHECK(r.valid == expect_valid);
  CHECK(r.mesh.degree() == o.p);
}

}  // namespace

TEST_CASE("boundary layer pipeline: 2D quarter annulus, curved circular wall") {
  const auto in = quarter_annulus(4, 8);
  const int wall = side_tag<2>(0);  // r = 0.5
  hom::GeometryModel<2> g;
  g.add_curve(wall, hom::Circle<2>(Eigen::Vector2d::Zero(), 0.5));
  hom::BoundaryLayerPipelineOptions o;
  o.layer = {.first_height = 0.01, .growth = 2.0, .layers = 3};
  o.p = 3;
  const auto r = hom::boundary_layer_pipeline<2>(in, {wall}, g, o);
  check_pipeline<2>(r, in, o);
  CHECK_FALSE(r.certification);  // no certify stage unless asked
  // Every node of the final wall lies on the circle.
  int on_wall = 0;
  for (const auto& f : r.mesh.boundary_facets())
    if (f.entity_tag == wall)
      for (int n : r.mesh.facet_node_ids(f)) {
        CHECK(r.mesh.node(n).norm() == doctest::Approx(0.5).epsilon(1e-12));
        ++on_wall;
      }
  CHECK(on_wall > 0);
  // After smoothing, the first level has (about) its prescribed height: the
  // level-0 elements' vertices lie within [0, h0] of the wall, with some at h0.
  double top = 0.0;
  for (int e = 0; e < r.smoothed.num_elements(); ++e)
    if (r.layer.level[e] == 0)
      for (int v = 0; v < 3; ++v) top = std::max(top, r.smoothed.node(r.smoothed.vertex(e, v)).norm() - 0.5);
  CHECK(top == doctest::Approx(o.layer.first_height).epsilon(0.2));
}

TEST_CASE("boundary layer pipeline: 3D cube, flat wall") {
  const auto in = box<3>(2);
  const int wall = side_tag<3>(2);  // z = 0
  hom::GeometryModel<3> g;
  g.add_surface(wall, hom::Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
  hom::BoundaryLayerPipelineOptions o;
  o.layer = {.first_height = 0.02, .growth = 2.0, .layers = 2};
  o.p = 2;
  const auto r = hom::boundary_layer_pipeline<3>(in, {wall}, g, o);
  check_pipeline<3>(r, in, o);
  // A flat wall: curving moves nothing, so (d) is (c) elevated, quality 1.
  CHECK(r.stages[3].quality.min == doctest::Approx(1.0));
}

TEST_CASE("boundary layer pipeline: a tangled smoothed linear mesh stops the pipeline at (c)") {
  // H = 0.3 + 0.6 + 1.2 = 2.1, twice the annulus's thickness: the layer's
  // nodes on the wall border are held at their heights outside the domain,
  // so no smoothing can untangle (c).
  const auto in = quarter_annulus(4, 8);
  const int wall = side_tag<2>(0);
  hom::GeometryModel<2> g;
  g.add_curve(wall, hom::Circle<2>(Eigen::Vector2d::Zero(), 0.5));
  hom::BoundaryLayerPipelineOptions o;
  o.layer = {.first_height = 0.3, .growth = 2.0, .layers = 3};
  o.p = 3;
  o.linear_optimize.max_iterations = 20;
  o.high_order_optimize.max_iterations = 5;
  const auto r = hom::boundary_layer_pipeline<2>(in, {wall}, g, o);
  REQUIRE(r.stages.size() == 3);
  CHECK(r.stages.back().name == "smoothed");
  CHECK(r.stages.back().quality.inverted > 0);
  CHECK(r.stopped_after_smoothing);
  CHECK_FALSE(r.valid);
  // The result is the (c) mesh, and final_ideal() is what (c) was measured
  // against: measuring again gives the same count.
  CHECK(r.mesh.degree() == 1);
  CHECK(r.mesh.nodes() == r.smoothed.nodes());
  const auto q = hom::mesh_quality(r.mesh, hom::ShapeMeasure{}, r.final_ideal(),
                                   hom::quadrature_for<hom::Simplex<2>, hom::DefaultExactness>(1));
  CHECK(q.quality_statistics().inverted == r.stages.back().quality.inverted);

  // With the stop off, (d) and (e) run on the same (c) and cannot end valid.
  o.stop_if_smoothed_invalid = false;
  const auto all = hom::boundary_layer_pipeline<2>(in, {wall}, g, o);
  REQUIRE(all.stages.size() == 5);
  CHECK_FALSE(all.stopped_after_smoothing);
  CHECK(all.stages[2].quality.inverted == r.stages[2].quality.inverted);
  CHECK(all.mesh.degree() == 3);
  CHECK_FALSE(all.valid);
}

TEST_CASE("boundary layer pipeline: stage (e) certified and repaired on request") {
  const auto in = quarter_annulus(4, 8);
  const int wall = side_tag<2>(0);
  hom::GeometryModel<2> g;
  g.add_curve(wall, hom::Circle<2>(Eigen::Vector2d::Zero(), 0.5));
  hom::BoundaryLayerPipelineOptions o;
  o.layer = {.first_height = 0.01, .growth = 2.0, .layers = 3};
  o.p = 4;
  o.high_order_optimize.certify = true;
  const auto r = hom::boundary_layer_pipeline<2>(in, {wall}, g, o);
  check_pipeline<2>(r, in, o);
  REQUIRE(r.certification);
  CHECK(r.certification->certified());
  CHECK(r.certification->valid == r.mesh.num_elements());
  // An independent certificate of the result agrees.
  const auto c = hom::certify_mesh(r.mesh, hom::CertifyOptions{});
  CHECK(c.valid == r.mesh.num_elements());
  CHECK(c.min_scaled_jacobian > 0.0);
}

TEST_CASE("boundary layer: midpoints projected onto their own wall entities, the shared edge onto both") {
  // Walls x = 0 and z = 0 of the cube, meeting along the edge x = z = 0 (two
  // mesh edges there). Record what each midpoint's projection is asked.
  const auto in = box<3>(2);
  const int a = side_tag<3>(0), b = side_tag<3>(2);
  std::vector<std::vector<int>> asked;
  const hom::WallProjection<3> record = [&](const Eigen::Vector3d& x, const std::vector<int>& entities) {
    asked.push_back(entities);
    return x;
  };
  const auto bl = hom::insert_boundary_layer(in, {a, b}, {.first_height = 0.02, .layers = 2}, record);
  REQUIRE(!asked.empty());
  int shared = 0;
  for (const auto& e : asked) {
    REQUIRE(!e.empty());
    CHECK(std::is_sorted(e.begin(), e.end()));
    if (e.size() == 2) {
      CHECK(e == std::vector<int>{std::min(a, b), std::max(a, b)});
      ++shared;
    } else {
      CHECK(e.size() == 1);
      CHECK((e[0] == a || e[0] == b));
    }
  }
  CHECK(shared == 2);
  REQUIRE(bl.facet_tags.size() == std::size_t(bl.num_wall_facets));
  for (int t : bl.facet_tags) CHECK((t == a || t == b));
}

TEST_CASE("boundary layer pipeline: a point on several wall entities goes to their intersection") {
  hom::GeometryModel<3> g;
  g.add_surface(1, hom::Sphere(Eigen::Vector3d::Zero(), 1.0));
  g.add_surface(2, hom::Plane(Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d x(0.7, 0.3, 0.6);
  // One entity: its closest point.
  const Eigen::Vector3d on_sphere = hom::detail::project_onto_wall_entities<3>(g, {1}, x);
  CHECK((on_sphere - x.normalized()).norm() < 1e-12);
  // Two: the circle |y| = 1, z = 0.5, where the nearest-entity projection
  // would leave the point on one of them only.
  const Eigen::Vector3d y = hom::detail::project_onto_wall_entities<3>(g, {1, 2}, x);
  CHECK(y.norm() == doctest::Approx(1.0).epsilon(1e-10));
  CHECK(y.z() == doctest::Approx(0.5).epsilon(1e-10));
  // ... in the meridian plane of x, as the circle's closest point is.
  CHECK(std::abs(y.x() * x.y() - y.y() * x.x()) < 1e-10);
  const Eigen::Vector3d nearest = hom::detail::project_to_nearest_wall<3>(g, {1, 2}, x);
  CHECK(std::abs(nearest.norm() - 1.0) + std::abs(nearest.z() - 0.5) > 1e-3);
}

namespace {

/// Box-state tag of structured.hpp for (r, theta, z) = (a, b, c), 0 lo, 1 hi, 2 inside.
int box_tag(int a, int b, int c) { return hom::detail::box_entity_tag<3>(hom::detail::BoxState<3>{a, b, c}); }

/// Quarter of a cylindrical shell 0.5 <= r <= 1.5, 0 <= theta <= pi / 2,
/// 0 <= z <= 0.5 of tetrahedra: structured.hpp's (r, theta, z) box mapped to
/// Cartesian coordinates (det = r > 0), with the model entities of the box.
SimplexMesh<3> quarter_shell(int nr, int nt, int nz) {
  auto m = hom::structured_mesh<hom::Simplex<3>>({nr, nt, nz}, Eigen::Vector3d(0.5, 0.0, 0.0),
                                                 Eigen::Vector3d(1.5, std::numbers::pi / 2, 0.5));
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Eigen::Vector3d q = m.node(i);
    m.node(i) = Eigen::Vector3d(q[0] * std::cos(q[1]), q[0] * std::sin(q[1]), q[2]);
  }
  m.reset_ideal();
  return m;
}

}  // namespace

TEST_CASE("boundary layer pipeline: a coarse curved wall meeting side planes (a wing's leading edge at the box faces)") {
  // The wing case's failure, small: the wall r = 0.5 has 2 facets over 90
  // degrees, so an edge's midpoint projected onto the cylinder lies s = 0.038
  // above its chord, and the vertex normals at its ends differ by 45 degrees:
  // the straight top edge of the unsplit facet is only H cos(22.5 deg) = 0.065
  // above the chord (H = 0.07), below s + H_2 = 0.068. With nz = 1 every wall vertex and
  // every wall edge along theta lies on the planes z = 0 and z = 0.5, where
  // the layer's nodes are held (not smoothed): they must be placed valid
  // (boundary_layer.hpp, "Full-height positions") and carried with the wall
  // at (d) (carry_wall_curving), and the wall-border midpoints next to a
  // corner of the model must be on the border arc (not fixed on the chord).
  const auto in = quarter_shell(2, 2, 1);
  const int wall = box_tag(0, 2, 2);
  hom::GeometryModel<3> g;
  g.add_surface(wall, hom::Cylinder(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.5));
  g.add_surface(box_tag(2, 2, 0), hom::Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
  g.add_surface(box_tag(2, 2, 1), hom::Plane(Eigen::Vector3d(0.0, 0.0, 0.5), Eigen::Vector3d::UnitZ()));
  g.add_surface(box_tag(2, 0, 2), hom::Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitY()));
  g.add_surface(box_tag(2, 1, 2), hom::Plane(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX()));
  g.add_curve(box_tag(0, 2, 0), hom::Circle<3>(Eigen::Vector3d::Zero(), 0.5, Eigen::Vector3d::UnitZ()));
  g.add_curve(box_tag(0, 2, 1), hom::Circle<3>(Eigen::Vector3d(0.0, 0.0, 0.5), 0.5, Eigen::Vector3d::UnitZ()));
  hom::BoundaryLayerPipelineOptions o;
  o.layer = {.first_height = 0.01, .growth = 2.0, .layers = 3};
  o.p = 2;
  const auto r = hom::boundary_layer_pipeline<3>(in, {wall}, g, o);
  REQUIRE(r.stages.size() >= 3);
  CHECK(r.stages[2].quality.inverted == 0);  // was 4: transitions over the border midpoints
  REQUIRE_FALSE(r.stopped_after_smoothing);
  // Valid: det > 0 at every node too. Without the side planes optimized on
  // their surfaces at the start of (e), two transition elements at the
  // border, 6 of whose 10 nodes the volume optimizer holds on the planes,
  // keep det < 0 at a node (min scaled Jacobian -0.044), which no
  // quadrature point sees.
  check_pipeline<3>(r, in, o);
  CHECK(r.stages[4].scaled_jacobian.min > 0.0);
  CHECK(r.boundary_face_iterations > 0);
  auto held = o;
  held.optimize_side_faces = false;
  const auto rh = hom::boundary_layer_pipeline<3>(in, {wall}, g, held);
  check_pipeline<3>(rh, in, held, /*expect_valid=*/false);
  CHECK(rh.stages[4].scaled_jacobian.min < 0.0);
  CHECK(rh.boundary_face_iterations == 0);
  // The wall-border midpoints are on the arcs, and so is every final node of
  // the wall's boundary facets.
  for (int n : r.layer.wall_nodes) {
    const auto x = r.layer.mesh.node(n);
    if (std::abs(x[2]) > 1e-12 && std::abs(x[2] - 0.5) > 1e-12) continue;
    const auto& c = r.layer.mesh.node_class(n);
    CAPTURE(n);
    CHECK((c.kind == hom::NodeKind::on_entity || (c.kind == hom::NodeKind::fixed && c.entity && c.entity->dim == 0)));
  }
  for (const auto& f : r.mesh.boundary_facets())
    if (f.entity_tag == wall)
      for (int n : r.mesh.facet_node_ids(f)) CHECK(r.mesh.node(n).head<2>().norm() == doctest::Approx(0.5).epsilon(1e-12));
  // The layer's nodes on the side planes, carried with the wall at (d), keep
  // parameters that give their positions.
  int with_params = 0;
  for (int i = 0; i < r.mesh.num_nodes(); ++i) {
    const auto& c = r.mesh.node_class(i);
    if (c.kind != hom::NodeKind::on_entity || !c.entity || c.entity->dim != 2 || c.entity->tag == wall) continue;
    if (c.num_params != 2) continue;
    ++with_params;
    CHECK((g.surface(c.entity->tag)->evaluate({c.params[0], c.params[1]}) - r.mesh.node(i)).norm() < 1e-12);
  }
  CHECK(with_params > 0);
}
