// The OpenCASCADE layer (src/cad): CAD faces and edges as hom surfaces and
// curves (against the analytic models and finite differences), projection
// and arc length, reading and writing STEP / IGES / BREP with clear errors,
// the built-in models, meshing a model with Gmsh with every boundary node
// classified on it, and classifying a given mesh by projection. If
// ../shared/data/cad exists, its real CAD files are read too.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Geom2d_Line.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax2.hxx>
#include <gp_Elips.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

#include "cad_mesher.hpp"
#include "cad_model.hpp"
#include "ears.hpp"
#include "mesh_ears.hpp"
#include "hom/geometry/cylinder.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "hom/nodes/gauss_lobatto.hpp"

using namespace hom;
using hom::cad::CadModel;

namespace {

constexpr double pi = std::numbers::pi;

// A fresh temporary directory, removed at the end of the test.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::random_device rd;
    path = std::filesystem::temp_directory_path() / ("hom_test_cad_" + std::to_string(rd()));
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

// The first face of the model whose surface is of `type`.
int face_of_type(const CadModel& m, const std::string& type) {
  for (int f = 1; f <= m.num_faces(); ++f)
    if (m.surface(f).type() == type) return f;
  return 0;
}

// Random (u, v) inside a face's parameter box (away from its bounds by
// `margin` of its size).
Eigen::Vector2d random_uv(const cad::OccSurface& s, std::mt19937& rng, double margin = 0.02) {
  std::uniform_real_distribution<double> t(margin, 1.0 - margin);
  Eigen::Vector2d uv;
  for (int k = 0; k < 2; ++k) {
    const auto r = s.range(k);
    uv[k] = r.lo + t(rng) * (r.hi - r.lo);
  }
  return uv;
}

// S_u, S_v and S_uu, S_uv, S_vv against central differences.
template <class S>
void check_derivatives_fd(const S& s, const Eigen::Vector2d& uv, double scale) {
  const double h = 1e-6;
  const Eigen::Vector2d du(h, 0), dv(0, h);
  const auto d = s.derivatives(uv);
  const Eigen::Vector3d fu = (s.evaluate(uv + du) - s.evaluate(uv - du)) / (2 * h);
  const Eigen::Vector3d fv = (s.evaluate(uv + dv) - s.evaluate(uv - dv)) / (2 * h);
  CHECK((d.col(0) - fu).norm() <= 1e-7 * scale);
  CHECK((d.col(1) - fv).norm() <= 1e-7 * scale);
  const auto dd = s.second_derivatives(uv);
  const Eigen::Matrix<double, 3, 2> d_u = (s.derivatives(uv + du) - s.derivatives(uv - du)) / (2 * h);
  const Eigen::Matrix<double, 3, 2> d_v = (s.derivatives(uv + dv) - s.derivatives(uv - dv)) / (2 * h);
  CHECK((dd.uu - d_u.col(0)).norm() <= 1e-6 * scale);
  CHECK((dd.uv - d_u.col(1)).norm() <= 1e-6 * scale);
  CHECK((dd.uv - d_v.col(0)).norm() <= 1e-6 * scale);
  CHECK((dd.vv - d_v.col(1)).norm() <= 1e-6 * scale);
}

// The OCC face and the analytic surface are the same parameterization up
// to a shift of the parameters (the frames may differ by a rotation about
// the axis): values, first and second derivatives agree at uv and uv + shift.
template <class A>
void check_against_analytic(const cad::OccSurface& occ, const A& analytic, double scale, int samples = 40) {
  std::mt19937 rng(7);
  const Eigen::Vector2d uv0 = random_uv(occ, rng, 0.2);
  const Eigen::Vector2d shift = analytic.project(occ.evaluate(uv0)) - uv0;
  for (int i = 0; i < samples; ++i) {
    const Eigen::Vector2d uv = random_uv(occ, rng, 0.05);
    const Eigen::Vector2d uva = uv + shift;
    CHECK((occ.evaluate(uv) - analytic.evaluate(uva)).norm() <= 1e-12 * scale);
    CHECK((occ.derivatives(uv) - analytic.derivatives(uva)).norm() <= 1e-12 * scale);
    const auto a = occ.second_derivatives(uv), b = analytic.second_derivatives(uva);
    CHECK((a.uu - b.uu).norm() <= 1e-12 * scale);
    CHECK((a.uv - b.uv).norm() <= 1e-12 * scale);
    CHECK((a.vv - b.vv).norm() <= 1e-12 * scale);
    check_derivatives_fd(occ, uv, scale);
  }
}

// x = S(uv) projects back onto x; a point moved along the normal projects to
// the same parameters.
void check_projection_round_trip(const cad::OccSurface& s, const Eigen::Vector2d& uv, double tol) {
  const Eigen::Vector3d x = s.evaluate(uv);
  const Eigen::Vector2d p = s.project(x);
  CHECK((s.evaluate(p) - x).norm() <= tol);
  for (int k = 0; k < 2; ++k) {
    const auto r = s.range(k);
    CHECK(p[k] >= r.lo - 1e-12);
    CHECK(p[k] <= r.hi + 1e-12);
    if (r.periodic) CHECK(p[k] < r.hi);
  }
}

std::filesystem::path shared_cad_dir() {
  if (const char* env = std::getenv("HOM_CAD_DATA")) return env;
  return std::filesystem::absolute(std::filesystem::path(__FILE__)).parent_path() / ".." / ".." / "shared" / "data" / "cad";
}

}  // namespace

TEST_CASE("OCC sphere face is hom's Sphere") {
  const Eigen::Vector3d c(1.0, -2.0, 0.5);
  const double r = 1.7;
  const auto m = cad::sphere_model(c, r);
  REQUIRE(m.num_faces() == 1);
  const auto s = m.surface(1);
  CHECK(s.type() == "sphere");
  CHECK(s.range(0).periodic);
  CHECK(s.range(0).length() == doctest::Approx(2 * pi));
  CHECK_FALSE(s.range(1).periodic);
  CHECK(s.range(1).lo == doctest::Approx(-pi / 2));
  CHECK(s.range(1).hi == doctest::Approx(pi / 2));
  check_against_analytic(s, Sphere(c, r), r);

  // Projection: round trips everywhere, across the seam and at the poles.
  std::mt19937 rng(3);
  for (int i = 0; i < 50; ++i) check_projection_round_trip(s, random_uv(s, rng, 0.0), 1e-12 * r);
  const auto ru = s.range(0);
  for (double u : {ru.lo, ru.lo + 1e-10, ru.hi - 1e-10, ru.lo - 1e-3, ru.hi + 1e-3})
    for (double v : {-1.0, 0.0, 0.3, pi / 2 - 1e-7, -pi / 2 + 1e-9}) {
      check_projection_round_trip(s, {u, v}, 1e-11 * r);
      // Off the surface: along the radius, the closest point is radial.
      const Eigen::Vector3d x = s.evaluate({u, v});
      const Eigen::Vector3d out = c + 1.3 * (x - c);
      CHECK((s.evaluate(s.project(out)) - x).norm() <= 1e-9 * r);
    }
  // The poles themselves (any longitude).
  for (double sgn : {-1.0, 1.0}) {
    const Eigen::Vector3d pole = c + sgn * r * Eigen::Vector3d::UnitZ();
    CHECK((s.evaluate(s.project(pole)) - pole).norm() <= 1e-9 * r);
  }
}

TEST_CASE("OCC cylinder and plane faces are hom's Cylinder and Plane") {
  const Eigen::Vector3d base(0.5, 0.25, -1.0), axis = Eigen::Vector3d(1, 2, 2).normalized();
  const double r = 0.8, h = 3.0;
  const auto m = cad::cylinder_model(base, axis, r, h);
  CHECK(m.num_faces() == 3);
  CHECK(m.surface_types().at("cylinder") == 1);
  CHECK(m.surface_types().at("plane") == 2);
  const int lateral = face_of_type(m, "cylinder");
  REQUIRE(lateral > 0);
  const auto s = m.surface(lateral);
  CHECK(s.range(0).periodic);
  CHECK(s.range(1).lo == doctest::Approx(0.0));
  CHECK(s.range(1).hi == doctest::Approx(h));
  check_against_analytic(s, Cylinder(base, axis, r), std::max(r, h));
  std::mt19937 rng(5);
  for (int i = 0; i < 30; ++i) check_projection_round_trip(s, random_uv(s, rng, 0.0), 1e-12 * h);
  // Across the seam: points at u = lo +- eps project next to each other.
  const double lo = s.range(0).lo;
  const Eigen::Vector2d a = s.project(s.evaluate({lo + 1e-9, 1.0})), b = s.project(s.evaluate({lo - 1e-9, 1.0}));
  CHECK(std::abs(s.range(0).unwrap(a[0], b[0]) - b[0]) == doctest::Approx(2e-9).epsilon(1e-3));

  for (int f = 1; f <= m.num_faces(); ++f) {
    if (f == lateral) continue;
    const auto p = m.surface(f);
    CHECK_FALSE(p.range(0).periodic);
    const Eigen::Matrix<double, 3, 2> d = p.derivatives({0, 0});
    const Plane plane(p.evaluate({0, 0}), d.col(0).cross(d.col(1)), d.col(0));
    check_against_analytic(p, plane, r, 10);
    // The cap's plane is perpendicular to the axis, at height 0 or h.
    CHECK(std::abs(plane.normal().dot(axis)) == doctest::Approx(1.0));
    const double height = (p.evaluate({0.1, 0.2}) - base).dot(axis);
    CHECK(std::min(std::abs(height), std::abs(height - h)) <= 1e-12);
    for (int i = 0; i < 10; ++i) check_projection_round_trip(p, random_uv(p, rng), 1e-12);
  }
}

TEST_CASE("OCC edges: derivatives, projection, arc length and its inverse") {
  const double r = 0.8, h = 3.0;
  const auto m = cad::cylinder_model(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), r, h);
  int circles = 0;
  std::mt19937 rng(11);
  for (int e = 1; e <= m.num_edges(); ++e) {
    REQUIRE_FALSE(m.degenerated(e));
    const auto c = m.curve(e);
    const auto range = c.range();
    if (c.type() == "circle") {
      ++circles;
      CHECK(range.periodic);
      CHECK(c.length() == doctest::Approx(2 * pi * r).epsilon(1e-12));
    } else {
      CHECK(c.type() == "line");  // the seam
      CHECK(c.length() == doctest::Approx(h).epsilon(1e-12));
    }
    std::uniform_real_distribution<double> t(range.lo, range.hi);
    for (int i = 0; i < 10; ++i) {
      const double u = t(rng), du = 1e-6;
      CHECK((c.derivative(u) - (c.evaluate(u + du) - c.evaluate(u - du)) / (2 * du)).norm() <= 1e-8);
      CHECK((c.second_derivative(u) - (c.derivative(u + du) - c.derivative(u - du)) / (2 * du)).norm() <= 1e-7);
      const Eigen::Vector3d x = c.evaluate(u);
      CHECK((c.evaluate(c.project(x)) - x).norm() <= 1e-12);
      // Arc length: s(u0, u) and its inverse.
      const double u0 = range.lo + 0.1 * range.length();
      const double s = c.arc_length(u0, u);
      if (c.type() == "circle") CHECK(s == doctest::Approx(r * (u - u0)).epsilon(1e-12));
      CHECK(c.parameter_at_length(u0, s) == doctest::Approx(u).epsilon(1e-11));
      CHECK(c.arc_length(u, u0) == doctest::Approx(-s));
    }
  }
  CHECK(circles == 2);

  // NURBS edges (rational quadratic quarter circles): the arc length is
  // exact pi r / 2, and the parameter at a fraction of it lands on the
  // circle at that angle.
  const Eigen::Vector3d center(0.1, 0.2, 0.3);
  const double rs = 0.5;
  const auto sphere = cad::nurbs_sphere_model(center, rs);
  int quarters = 0;
  for (int e = 1; e <= sphere.num_edges(); ++e) {
    if (sphere.degenerated(e)) continue;
    const auto c = sphere.curve(e);
    CHECK(c.type() == "bspline");
    CHECK(c.length() == doctest::Approx(pi * rs / 2).epsilon(1e-10));
    const auto range = c.range();
    const Eigen::Vector3d a = c.evaluate(range.lo) - center, b = c.evaluate(range.hi) - center;
    for (double f : {0.1, 1.0 / 3.0, 0.5, 0.9}) {
      const double u = c.parameter_at_length(range.lo, f * c.length());
      const Eigen::Vector3d x = c.evaluate(u) - center;
      CHECK(x.norm() == doctest::Approx(rs).epsilon(1e-12));
      CHECK(std::acos(std::clamp(x.dot(a) / (rs * rs), -1.0, 1.0)) == doctest::Approx(f * pi / 2).epsilon(1e-9));
      CHECK(std::acos(std::clamp(x.dot(b) / (rs * rs), -1.0, 1.0)) == doctest::Approx((1 - f) * pi / 2).epsilon(1e-9));
    }
    ++quarters;
  }
  CHECK(quarters == 12);  // 4 on the equator, 8 meridian quarters
}

TEST_CASE("NURBS sphere: 8 exact rational patches, one closed solid") {
  const Eigen::Vector3d c(0.1, 0.2, 0.3);
  const double r = 0.5;
  const auto m = cad::nurbs_sphere_model(c, r);
  CHECK(m.num_solids() == 1);
  CHECK(m.num_shells() == 1);
  CHECK(m.inner_shell_faces().empty());  // a solid ball has no cavity
  CHECK(m.num_faces() == 8);
  CHECK(m.surface_types().at("bspline") == 8);
  CHECK(m.valid());
  CHECK(m.volume() == doctest::Approx(4.0 / 3.0 * pi * r * r * r).epsilon(1e-6));
  CHECK(m.area() == doctest::Approx(4 * pi * r * r).epsilon(1e-6));
  std::mt19937 rng(13);
  for (int f = 1; f <= 8; ++f) {
    const auto s = m.surface(f);
    CHECK_FALSE(s.range(0).periodic);
    CHECK_FALSE(s.range(1).periodic);
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector2d uv = random_uv(s, rng, 0.0);
      CHECK((s.evaluate(uv) - c).norm() == doctest::Approx(r).epsilon(1e-13));
      // The outward normal (reversed faces flip it) points away from the centre.
      const auto d = s.derivatives(uv);
      const Eigen::Vector3d n = (s.reversed() ? -1.0 : 1.0) * d.col(0).cross(d.col(1));
      if (n.norm() > 1e-8) CHECK(n.dot(s.evaluate(uv) - c) > 0);
      check_derivatives_fd(s, random_uv(s, rng, 0.05), r);
      check_projection_round_trip(s, uv, 1e-11);
      // A point off the sphere projects radially.
      const Eigen::Vector3d x = s.evaluate(uv), out = c + 1.2 * (x - c);
      CHECK((s.evaluate(s.project(out)) - x).norm() <= 1e-9);
      CHECK(s.contains(uv));
    }
  }
}

TEST_CASE("cube with a spherical cavity built with OpenCASCADE") {
  const auto m = cad::cube_with_cavity_model();
  CHECK(m.num_solids() == 1);
  CHECK(m.num_faces() == 7);
  CHECK(m.surface_types().at("plane") == 6);
  CHECK(m.surface_types().at("sphere") == 1);
  CHECK(m.valid());
  CHECK(m.volume() == doctest::Approx(125.0 - 4.0 / 3.0 * pi * 0.125).epsilon(1e-9));
  const auto box = m.bounding_box();
  CHECK(box[0].norm() <= 1e-6);
  CHECK((box[1] - Eigen::Vector3d::Constant(5.0)).norm() <= 1e-6);
  const int sphere = face_of_type(m, "sphere");
  REQUIRE(sphere > 0);
  check_against_analytic(m.surface(sphere), Sphere(Eigen::Vector3d::Constant(2.5), 0.5), 0.5, 10);
  // The geometry model has every face and every edge with a curve.
  const auto g = m.geometry_model();
  CHECK(int(g.surfaces().size()) == 7);
  int curves = 0;
  for (int e = 1; e <= m.num_edges(); ++e) curves += !m.degenerated(e);
  CHECK(int(g.curves().size()) == curves);
  CHECK(m.summary().find("1 solid, 2 shells, 7 faces") != std::string::npos);  // the cavity is a shell
  // The cavity's shell is the inner one: its sphere is the only inner-shell face.
  CHECK(m.inner_shell_faces() == std::vector<int>{sphere});
  // Every edge's ends are its vertices; pcurves land on the same points.
  for (int e = 1; e <= m.num_edges(); ++e) {
    if (m.degenerated(e)) continue;
    const auto c = m.curve(e);
    const auto v = m.edge_vertices(e);
    CHECK((c.evaluate(c.range().lo) - m.vertex(v[0])).norm() <= 1e-7);
    CHECK((c.evaluate(c.range().hi) - m.vertex(v[1])).norm() <= 1e-7);
    for (int f : m.edge_faces(e)) {
      const double t = c.range().lo + 0.37 * c.range().length();
      CHECK((m.surface(f).evaluate(m.edge_uv_on_face(e, f, t)) - c.evaluate(t)).norm() <= 1e-7);
    }
  }
}

TEST_CASE("write and read back BREP, STEP and IGES") {
  const TempDir dir;
  const auto m = cad::cube_with_cavity_model();
  for (const std::string name : {"cube.brep", "cube.STEP", "cube.stp", "cube.igs", "cube.IGES"}) {
    CAPTURE(name);
    const std::string path = dir / name;
    cad::write_cad(m, path);
    REQUIRE(std::filesystem::exists(path));
    const auto back = cad::read_cad(path);
    CHECK(back.name() == path);
    CHECK(back.num_faces() == 7);
    CHECK(back.num_solids() == 1);
    CHECK(back.surface_types() == m.surface_types());
    CHECK(back.volume() == doctest::Approx(m.volume()).epsilon(1e-6));
    const auto b0 = m.bounding_box(), b1 = back.bounding_box();
    CHECK((b0[0] - b1[0]).norm() <= 1e-5);
    CHECK((b0[1] - b1[1]).norm() <= 1e-5);
    // The sphere is still the sphere.
    const int s = face_of_type(back, "sphere");
    REQUIRE(s > 0);
    std::mt19937 rng(1);
    for (int i = 0; i < 5; ++i)
      CHECK((back.surface(s).evaluate(random_uv(back.surface(s), rng)) - Eigen::Vector3d::Constant(2.5)).norm() ==
            doctest::Approx(0.5).epsilon(1e-12));
  }
  // No temporary is left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path)) files += e.path().string().find(".tmp") == std::string::npos;
  CHECK(files == 5);
}

TEST_CASE("CAD read errors name the file") {
  const TempDir dir;
  auto message = [](const std::string& path) -> std::string {
    try {
      cad::read_cad(path);
    } catch (const cad::CadError& e) {
      return e.what();
    }
    return "";
  };
  const std::string missing = dir / "missing.step";
  CHECK(message(missing).find(missing) == 0);
  CHECK(message(missing).find("no such file") != std::string::npos);

  const std::string unknown = dir / "model.xyz";
  std::ofstream(unknown) << "solid\n";
  CHECK(message(unknown).find(unknown) == 0);
  CHECK(message(unknown).find("unsupported") != std::string::npos);

  for (const std::string name : {"garbage.step", "garbage.iges", "garbage.brep"}) {
    const std::string path = dir / name;
    std::ofstream(path) << "this is not a CAD file\n" << std::string(200, 'x') << "\n";
    const std::string msg = message(path);
    CAPTURE(msg);
    CHECK(msg.find(path) == 0);
  }
  const std::string empty = dir / "empty.brep";
  std::ofstream(empty).close();
  CHECK(message(empty).find(empty) == 0);
  CHECK(message(empty).find("empty") != std::string::npos);

  // A well-formed STEP file without any shape.
  const std::string no_shape = dir / "no_shape.step";
  std::ofstream(no_shape) << "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
                             "FILE_NAME('x','2024-01-01T00:00:00',(''),(''),'','','');\n"
                             "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\nENDSEC;\n"
                             "END-ISO-10303-21;\n";
  CHECK(message(no_shape).find(no_shape) == 0);

  const std::string directory = dir / "dir.brep";
  std::filesystem::create_directories(directory);
  CHECK(message(directory).find(directory) == 0);
  CHECK_THROWS_AS(cad::cad_format("a.stl"), cad::CadError);
  CHECK(cad::cad_format("A.StP") == cad::CadFormat::step);
  CHECK(cad::cad_format("a.IGS") == cad::CadFormat::iges);
}

TEST_CASE("meshing the cube with a cavity: every boundary node on the CAD") {
  const auto m = cad::cube_with_cavity_model();
  cad::CadMeshOptions o;
  o.size = 1.62;
  for (int v = 1; v <= m.num_vertices(); ++v)
    o.vertex_sizes[v] = (m.vertex(v) - Eigen::Vector3d::Constant(2.5)).norm() < 1.0 ? 0.2 : 1.62;
  bool remeshed = false;  // (no face needs MeshAdapt here)
  o.progress = [&](const std::string&) { remeshed = true; };
  const auto mesh = cad::mesh_cad<Simplex<3>>(m, o);
  CHECK(!remeshed);
  CHECK(mesh.num_elements() > 1200);
  CHECK(mesh.num_elements() < 1700);
  const auto g = m.geometry_model();
  const int sphere = face_of_type(m, "sphere");
  int on[3] = {0, 0, 0};
  std::set<int> faces_seen;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const auto& c = mesh.node_class(i);
    if (c.kind == NodeKind::free) continue;
    REQUIRE(c.entity);
    const Eigen::Vector3d x = mesh.node(i);
    ++on[c.entity->dim];
    if (c.entity->dim == 0) {
      CHECK(c.kind == NodeKind::fixed);
      CHECK((m.vertex(c.entity->tag) - x).norm() < 1e-8);
    } else if (c.entity->dim == 1) {
      REQUIRE(c.num_params == 1);
      CHECK((g.curve(c.entity->tag)->evaluate(c.params[0]) - x).norm() < 1e-8);
    } else {
      REQUIRE(c.entity->dim == 2);
      REQUIRE(c.num_params == 2);
      CHECK((g.surface(c.entity->tag)->evaluate({c.params[0], c.params[1]}) - x).norm() < 1e-8);
      CHECK(m.surface(c.entity->tag).contains({c.params[0], c.params[1]}));
      faces_seen.insert(c.entity->tag);
      if (c.entity->tag == sphere) CHECK((x - Eigen::Vector3d::Constant(2.5)).norm() == doctest::Approx(0.5));
    }
  }
  CHECK(on[0] == m.num_vertices());
  CHECK(on[1] > 0);
  CHECK(int(faces_seen.size()) == 7);
  // Boundary facets carry the model's face tags; nodes of a facet lie on
  // that face or its edges / vertices.
  CHECK(!mesh.boundary_facets().empty());
  for (const auto& f : mesh.boundary_facets()) {
    CHECK(f.entity_tag >= 1);
    CHECK(f.entity_tag <= 7);
    for (int v : f.vertices) {
      const auto& c = mesh.node_class(v);
      if (c.entity->dim == 2) CHECK(c.entity->tag == f.entity_tag);
      if (c.entity->dim == 1) {
        const auto ef = m.edge_faces(c.entity->tag);
        CHECK(std::find(ef.begin(), ef.end(), f.entity_tag) != ef.end());
      }
    }
  }
  for (int e = 0; e < mesh.num_elements(); ++e) CHECK(mesh.element_entities()[e] == 1);

  // Classifying the same mesh by projection (as a user-supplied mesh) gives
  // the same entities and points.
  auto copy = mesh;
  for (auto& c : copy.node_classes()) c = NodeClass{};
  copy.boundary_facets().clear();
  cad::classify(copy, m, 1e-8);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    const auto& a = mesh.node_class(i);
    const auto& b = copy.node_class(i);
    if (a.kind == NodeKind::free) {
      CHECK(b.kind == NodeKind::free);
      continue;
    }
    CHECK(a.kind == b.kind);
    CHECK(a.entity == b.entity);
    if (b.entity->dim == 2)
      CHECK((m.surface(b.entity->tag).evaluate({b.params[0], b.params[1]}) - copy.node(i)).norm() < 1e-8);
    if (b.entity->dim == 1) CHECK((m.curve(b.entity->tag).evaluate(b.params[0]) - copy.node(i)).norm() < 1e-8);
  }
  REQUIRE(copy.boundary_facets().size() == mesh.boundary_facets().size());
  std::multiset<int> fa, fb;
  for (const auto& f : mesh.boundary_facets()) fa.insert(f.entity_tag);
  for (const auto& f : copy.boundary_facets()) fb.insert(f.entity_tag);
  CHECK(fa == fb);

  // A boundary node moved off the model is an error that names it.
  int moved = -1;
  for (int i = 0; i < copy.num_nodes() && moved < 0; ++i)
    if (copy.node_class(i).kind != NodeKind::free) moved = i;
  copy.node(moved) += Eigen::Vector3d(1e-3, 2e-3, -1e-3);
  try {
    cad::classify(copy, m, 1e-8);
    FAIL("classify accepted a node off the model");
  } catch (const cad::MeshingError& e) {
    CHECK(std::string(e.what()).find("node " + std::to_string(moved)) != std::string::npos);
  }
}

namespace {

/// The mean length of the edges of `mesh` whose end points `keep` accepts.
template <class Keep>
double mean_edge_length(const Mesh<Simplex<3>>& mesh, Keep keep) {
  double sum = 0;
  int n = 0;
  const Topology<Simplex<3>> topology(mesh);
  for (const auto& [a, b] : topology.edges())
    if (keep(mesh.node(a), mesh.node(b))) sum += (mesh.node(a) - mesh.node(b)).norm(), ++n;
  REQUIRE(n > 0);
  return sum / n;
}

}  // namespace

TEST_CASE("local sizes (CadMeshOptions::local_sizes): finer inside the ball, even below size_min") {
  const auto m = cad::cube_with_cavity_model();
  const Eigen::Vector3d centre(5.0, 2.5, 2.5);  // on the cube's face x = 5, away from the cavity
  // The mean length of the edges whose midpoints lie within [r0, r1) of the ball's centre.
  auto mean_edge = [&](const Mesh<Simplex<3>>& mesh, double r0, double r1) {
    return mean_edge_length(mesh, [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      const double r = ((a + b) / 2 - centre).norm();
      return r >= r0 && r < r1;
    });
  };
  cad::CadMeshOptions o;
  o.size = 1.0;
  const auto plain = cad::mesh_cad<Simplex<3>>(m, o);
  CHECK(mean_edge(plain, 0.0, 0.5) > 0.6);
  o.local_sizes.push_back({centre, 1.0, 0.2});
  const auto refined = cad::mesh_cad<Simplex<3>>(m, o);
  CHECK(refined.num_elements() > plain.num_elements());
  CHECK(mean_edge(refined, 0.0, 0.5) < 0.35);
  // Two radii out (the ball's size grows back over one radius) the mesh is as coarse as before.
  CHECK(mean_edge(refined, 2.5, 3.5) > 0.8 * mean_edge(plain, 2.5, 3.5));
  // Gmsh's floor is global: a ball finer than size_min lowers it.
  o.size_min = 0.8;
  CHECK(mean_edge(cad::mesh_cad<Simplex<3>>(m, o), 0.0, 0.5) < 0.35);
  o.local_sizes.push_back({centre, -1.0, 0.2});
  CHECK_THROWS_AS(cad::mesh_cad<Simplex<3>>(m, o), std::invalid_argument);
}

TEST_CASE("earlier sizes (CadMeshOptions::earlier_sizes): a ball below size_min refines only itself") {
  // The cavity (radius 0.5 at the cube's centre) meshed by curvature at 24
  // elements per turn asks for 0.13, below the floor 0.3: the floor decides.
  const auto m = cad::cube_with_cavity_model();
  const Eigen::Vector3d cavity(2.5, 2.5, 2.5);
  cad::CadMeshOptions o;
  o.size = 1.0;
  o.size_min = 0.3;
  o.size_from_curvature = 24;
  const auto first = cad::mesh_cad<Simplex<3>>(m, o);
  const Topology<Simplex<3>> topology(first);
  const auto map = cad::size_map(first);
  REQUIRE(map.points.size() == map.sizes.size());
  REQUIRE(int(map.points.size()) == topology.num_vertices());
  {  // the first vertex's size is the mean length of its edges
    const int v = topology.vertices().front();
    double sum = 0;
    int n = 0;
    for (const auto& [a, b] : topology.edges())
      if (a == v || b == v) sum += (first.node(a) - first.node(b)).norm(), ++n;
    CHECK(map.sizes.front() == doctest::Approx(sum / n).epsilon(1e-12));
    CHECK((map.points.front() - first.node(v)).norm() == 0.0);
  }
  // A ball of size 0.1 at the cube's face x = 5, 2 away from the cavity.
  const Eigen::Vector3d centre(5.0, 2.5, 2.5);
  o.local_sizes.push_back({centre, 0.6, 0.1});
  // Without the earlier sizes Gmsh's floor falls to 0.1 for the whole model,
  // so the cavity is meshed at its curvature's 0.13 as well (half as fine);
  // with them, as the first mesh was.
  const auto lowered = cad::mesh_cad<Simplex<3>>(m, o);
  o.earlier_sizes = map;
  const auto local = cad::mesh_cad<Simplex<3>>(m, o);
  // The mean length of the edges with both ends within `r` of `x`.
  // The mean length of the edges within r of x.
  auto mean_edge_near = [](const Mesh<Simplex<3>>& mesh, const Eigen::Vector3d& x, double r) {
    return mean_edge_length(mesh, [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      return (a - x).norm() < r && (b - x).norm() < r;
    });
  };
  const double at_cavity = mean_edge_near(first, cavity, 0.6);
  CHECK(mean_edge_near(lowered, cavity, 0.6) < 0.7 * at_cavity);
  CHECK(mean_edge_near(local, cavity, 0.6) == doctest::Approx(at_cavity).epsilon(0.25));
  CHECK(local.num_elements() < lowered.num_elements());
  // Both refine the ball as it asks.
  CHECK(mean_edge_near(local, centre, 0.3) < 0.2);
  CHECK(mean_edge_near(lowered, centre, 0.3) < 0.2);
  // A bad entry is named.
  o.earlier_sizes.sizes[3] = std::nan("");
  CHECK_THROWS_WITH_AS(cad::mesh_cad<Simplex<3>>(m, o), doctest::Contains("earlier size 4"), std::invalid_argument);
  o.earlier_sizes.sizes.pop_back();
  CHECK_THROWS_WITH_AS(cad::mesh_cad<Simplex<3>>(m, o), doctest::Contains("sizes"), std::invalid_argument);
}

TEST_CASE("check_size_fields names the first bad ball or vertex size") {
  const auto m = cad::cube_with_cavity_model();
  auto message = [&](const cad::CadMeshOptions& o) -> std::string {
    try {
      cad::check_size_fields(m, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  cad::CadMeshOptions o;
  o.local_sizes.push_back({Eigen::Vector3d::Zero(), 1.0, 0.2});
  o.vertex_sizes[m.num_vertices()] = 0.3;
  CHECK(message(o).empty());
  o.local_sizes.push_back({Eigen::Vector3d(0, std::nan(""), 0), 1.0, 0.2});
  CHECK(message(o).find("local size 2") != std::string::npos);
  o.local_sizes.back().center.y() = 0;
  o.local_sizes.back().size = std::numeric_limits<double>::infinity();
  CHECK(message(o).find("local size 2") != std::string::npos);
  o.local_sizes.pop_back();
  o.vertex_sizes[m.num_vertices() + 1] = 0.3;
  CHECK(message(o).find("vertex " + std::to_string(m.num_vertices() + 1)) != std::string::npos);
  o.vertex_sizes.erase(m.num_vertices() + 1);
  o.vertex_sizes[1] = 0.0;
  CHECK(message(o).find("vertex 1:") != std::string::npos);
  // cad_mesh_data refuses them before meshing.
  CHECK_THROWS_AS(cad::cad_mesh_data(m, o), std::invalid_argument);
}

TEST_CASE("a body and its far field that share no faces: mesh one solid (CadMeshOptions::solids)") {
  // The ball and the cube with a spherical cavity around it, assembled: two
  // sphere faces on the interface, one per solid (like a ring in a sphere
  // region read from CAD).
  const Eigen::Vector3d c = Eigen::Vector3d::Constant(2.5);
  const auto m = cad::assemble({cad::sphere_model(c, 0.5), cad::cube_with_cavity_model(5.0, 1.0)}, "ball_in_box");
  REQUIRE(m.num_solids() == 2);
  REQUIRE(m.num_faces() == 1 + 7);
  CHECK(m.solid_faces(1) == std::vector<int>{1});  // the parts' order
  CHECK(m.surface(1).type() == "sphere");
  CHECK(m.inner_shell_faces().size() == 1);
  CHECK(m.inner_shell_faces().front() != 1);  // the far field's own copy of the sphere
  cad::CadMeshOptions o;
  o.size = 1.0;
  for (int v = 1; v <= m.num_vertices(); ++v)  // finer on the ball
    if ((m.vertex(v) - c).norm() < 1.0) o.vertex_sizes[v] = 0.25;
  auto mesh_of = [&](std::vector<int> solids) {
    o.solids = std::move(solids);
    return cad::cad_mesh_data(m, o);
  };
  auto count = [](const io::MshData& d, int dim) {
    return std::count_if(d.elements.begin(), d.elements.end(), [&](const auto& e) { return e.entity.dim == dim; });
  };
  const auto both = mesh_of({}), ball = mesh_of({1}), far = mesh_of({2});
  CHECK(count(ball, 3) > 0);
  CHECK(count(far, 3) > count(ball, 3));
  CHECK(count(ball, 3) + count(far, 3) == count(both, 3));
  CHECK(count(ball, 2) + count(far, 2) == count(both, 2));  // no face is shared
  CHECK(mesh_of({1, 2}).elements.size() == both.elements.size());
  // The far field alone: its solid's elements, its faces' facets, and no
  // node inside the ball; every node is used by an element.
  const auto far_faces = m.solid_faces(2);
  std::set<std::int64_t> used;
  for (const auto& e : far.elements) {
    if (e.entity.dim == 3) CHECK(e.entity.tag == 2);
    if (e.entity.dim == 2) CHECK(std::count(far_faces.begin(), far_faces.end(), e.entity.tag) == 1);
    for (auto n : far.nodes_of(e)) used.insert(n);
  }
  CHECK(used.size() == far.nodes.size());
  double nearest = 1e9;
  for (const auto& n : far.nodes) nearest = std::min(nearest, (Eigen::Vector3d(n.x[0], n.x[1], n.x[2]) - c).norm());
  CHECK(nearest == doctest::Approx(0.5).epsilon(1e-6));
  for (const auto& en : far.entities)
    if (en.id.dim == 3) CHECK(en.id.tag == 2);
  // The ball alone: every node in it.
  for (const auto& n : ball.nodes) CHECK((Eigen::Vector3d(n.x[0], n.x[1], n.x[2]) - c).norm() <= 0.5 + 1e-6);
  // Tetrahedra of the far field alone: its cavity's faces are boundary facets.
  o.solids = {2};
  const auto tets = cad::mesh_cad<Simplex<3>>(m, o);
  std::set<int> facet_faces;
  for (const auto& f : tets.boundary_facets()) facet_faces.insert(f.entity_tag);
  CHECK(facet_faces == std::set<int>(far_faces.begin(), far_faces.end()));
  // A solid the model lacks.
  CHECK_THROWS_AS(mesh_of({3}), cad::MeshingError);
  CHECK_THROWS_AS(mesh_of({0}), cad::MeshingError);
}

TEST_CASE("surface meshes of the NURBS sphere: triangles and quadrilaterals on the patches") {
  const Eigen::Vector3d c = Eigen::Vector3d::Zero();
  const auto m = cad::nurbs_sphere_model(c, 0.5);
  cad::CadMeshOptions o;
  o.size = 0.15;
  auto check = [&](const auto& mesh) {
    CHECK(mesh.num_elements() > 50);
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      const auto& cl = mesh.node_class(i);
      REQUIRE(cl.entity);
      CHECK(cl.kind != NodeKind::free);
      const Eigen::Vector3d x = mesh.node(i);
      CHECK(x.norm() == doctest::Approx(0.5).epsilon(1e-12));
      if (cl.entity->dim == 2) {
        REQUIRE(cl.num_params == 2);
        CHECK((m.surface(cl.entity->tag).evaluate({cl.params[0], cl.params[1]}) - x).norm() < 1e-8);
      }
    }
    std::set<int> faces(mesh.element_entities().begin(), mesh.element_entities().end());
    CHECK(faces == std::set<int>{1, 2, 3, 4, 5, 6, 7, 8});
  };
  check(cad::mesh_cad<Simplex<2>, WarpBlend, 3>(m, o));
  check(cad::mesh_cad<Cube<2>, GaussLobatto, 3>(m, o));
}

namespace {

// Appends the nodes of the triangle-ear tests, V = (0, 0), A = (1, 0.5),
// B = (-1, 0.5) and C = (0, 1.5), tagged 1 to 4, node k on entity on[k] with
// its (x, y) as parameters (as many as the entity's dimension).
void add_ear_test_nodes(io::MshData& d, const std::array<EntityId, 4>& on) {
  const std::vector<std::array<double, 3>> x = {{0, 0, 0}, {1, 0.5, 0}, {-1, 0.5, 0}, {0, 1.5, 0}};
  for (std::size_t k = 0; k < x.size(); ++k) {
    io::MshNode n;
    n.tag = std::int64_t(k) + 1;
    n.x = x[k];
    n.entity = on[k];
    n.num_params = on[k].dim;
    n.params = {x[k][0], x[k][1], 0.0};
    d.nodes.push_back(n);
  }
}

// Appends an element of Gmsh type `type` on entity (dim, tag) to d, tagged
// after the last one.
void add_msh_element(io::MshData& d, int type, int dim, int tag, const std::vector<std::int64_t>& nodes) {
  io::MshElement e;
  e.tag = std::int64_t(d.elements.size()) + 1;
  e.type = type;
  e.entity = {dim, tag};
  e.first = d.element_nodes.size();
  e.num_nodes = int(nodes.size());
  d.element_nodes.insert(d.element_nodes.end(), nodes.begin(), nodes.end());
  d.elements.push_back(e);
}

}  // namespace

TEST_CASE("a quadrilateral ear (two edges on one curve at a corner) is split into five, conforming, same winding") {
  // Face 1 is the plane z = 0 with (u, v) = (x, y); curve 1 runs along y = 0.
  // Quad A = (0,0) (1,0) (0,1) (-1,0) has both edges at (0,0) on curve 1: an
  // ear. Quad B = (1,0) (2,0) (2,1) (0,1) shares A's edge (1,0)-(0,1) and has
  // one edge on the curve: not an ear.
  io::MshData d;
  const std::vector<std::array<double, 3>> x = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {2, 0, 0}, {2, 1, 0}};
  for (std::size_t i = 0; i < x.size(); ++i) {
    io::MshNode n;
    n.tag = std::int64_t(i) + 1;
    n.x = x[i];
    const bool on_curve = x[i][1] == 0.0;
    n.entity = EntityId{on_curve ? 1 : 2, 1};
    n.num_params = on_curve ? 1 : 2;
    n.params = {x[i][0], x[i][1], 0.0};
    d.nodes.push_back(n);
  }
  auto add = [&](int type, int dim, std::vector<std::int64_t> nodes) { add_msh_element(d, type, dim, 1, nodes); };
  for (auto [a, b] : {std::pair{4, 1}, std::pair{1, 2}, std::pair{2, 5}}) add(1, 1, {a, b});
  add(3, 2, {1, 2, 3, 4});
  add(3, 2, {2, 5, 6, 3});
  const cad::FaceGeometry plane{[](int, const Eigen::Vector3d& p) { return Eigen::Vector2d(p.x(), p.y()); },
                                [](int, const Eigen::Vector2d& uv) { return Eigen::Vector3d(uv.x(), uv.y(), 0.0); }};
  CHECK(cad::split_quad_ears(d, plane) == 1);
  CHECK(d.nodes.size() == 10);
  std::map<std::int64_t, Eigen::Vector2d> at;
  for (const auto& n : d.nodes) at[n.tag] = Eigen::Vector2d(n.x[0], n.x[1]);
  int quads = 0, at_ear_corner = 0;
  std::map<std::pair<std::int64_t, std::int64_t>, int> edge_uses;
  for (const auto& e : d.elements) {
    if (e.type != 3) continue;
    ++quads;
    const auto n = d.nodes_of(e);
    double twice_area = 0.0;  // shoelace: positive for the input's counter-clockwise winding
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector2d a = at.at(n[i]), b = at.at(n[(i + 1) % 4]);
      twice_area += a.x() * b.y() - a.y() * b.x();
      ++edge_uses[{std::min(n[i], n[(i + 1) % 4]), std::max(n[i], n[(i + 1) % 4])}];
      // Each element's corners are strictly convex.
      const Eigen::Vector2d c = at.at(n[(i + 2) % 4]);
      CHECK((b - a).x() * (c - b).y() - (b - a).y() * (c - b).x() > 0.0);
    }
    CHECK(twice_area > 0.0);
    if (std::find(n.begin(), n.end(), 1) != n.end()) ++at_ear_corner;
  }
  CHECK(quads == 6);          // B and the five of A
  CHECK(at_ear_corner == 2);  // the ear's corner now has two elements
  // Conforming: every edge is used by one element (boundary) or two.
  int boundary = 0;
  for (const auto& [edge, uses] : edge_uses) {
    CHECK(uses <= 2);
    boundary += uses == 1;
  }
  CHECK(boundary == 6);  // the outline of A and B is unchanged: 6 edges
  for (const auto& n : d.nodes)
    if (n.tag > 6) {
      REQUIRE(n.entity);
      CHECK(n.entity->dim == 2);
      CHECK(n.num_params == 2);
      CHECK(n.params[0] == doctest::Approx(n.x[0]));
    }
  CHECK(cad::split_quad_ears(d, plane) == 0);  // nothing left to split
}

TEST_CASE("a triangle ear (two edges on one curve at a corner) is split into three at its centre, conforming") {
  // Face 1 is the plane z = 0 with (u, v) = (x, y); curve 1 (a parabola)
  // passes through B = (-1, 0.5), V = (0, 0) and A = (1, 0.5). Triangle
  // V A B has both edges at V on curve 1: an ear. Triangle A C B, C = (0, 1.5),
  // shares its edge A-B and has no edge on the curve. With V on the vertex
  // of closed curve 1, V A B is still an ear; with V on a vertex where curve
  // 2 (the edge B-V) meets curve 1, nothing is.
  for (const int v_dim : {1, 0, -1}) {
    CAPTURE(v_dim);
    io::MshData d;
    add_ear_test_nodes(d, {EntityId{std::max(v_dim, 0), 1}, EntityId{1, 1}, EntityId{1, 1}, EntityId{2, 1}});
    auto add = [&](int type, int dim, std::vector<std::int64_t> nodes) { add_msh_element(d, type, dim, 1, nodes); };
    add(1, 1, {3, 1});
    add(1, 1, {1, 2});
    if (v_dim < 0) d.elements[0].entity.tag = 2;
    add(2, 2, {1, 2, 3});
    add(2, 2, {2, 4, 3});
    const cad::FaceGeometry plane{[](int, const Eigen::Vector3d& p) { return Eigen::Vector2d(p.x(), p.y()); },
                                  [](int, const Eigen::Vector2d& uv) { return Eigen::Vector3d(uv.x(), uv.y(), 0.0); }};
    if (v_dim < 0) {
      CHECK(cad::split_triangle_ears(d, plane) == 0);
      CHECK(d.elements.size() == 4);
      continue;
    }
    CHECK(cad::split_triangle_ears(d, plane) == 1);
    REQUIRE(d.nodes.size() == 5);
    const auto& centre = d.nodes.back();
    CHECK(centre.x[0] == doctest::Approx(0.0));
    CHECK(centre.x[1] == doctest::Approx(1.0 / 3));
    REQUIRE(centre.entity);
    CHECK(centre.entity->dim == 2);
    CHECK(centre.num_params == 2);
    CHECK(centre.params[1] == doctest::Approx(1.0 / 3));
    std::map<std::int64_t, Eigen::Vector2d> at;
    for (const auto& n : d.nodes) at[n.tag] = Eigen::Vector2d(n.x[0], n.x[1]);
    std::set<std::int64_t> tags;
    std::map<std::pair<std::int64_t, std::int64_t>, int> edge_uses;
    int triangles = 0, at_ear_corner = 0;
    for (const auto& e : d.elements) {
      CHECK(tags.insert(e.tag).second);  // element tags stay unique
      if (e.type != 2) continue;
      ++triangles;
      const auto n = d.nodes_of(e);
      const Eigen::Vector2d a = at.at(n[0]), b = at.at(n[1]), c = at.at(n[2]);
      CHECK((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x() > 0.0);  // the input's winding
      for (int i = 0; i < 3; ++i) ++edge_uses[{std::min(n[i], n[(i + 1) % 3]), std::max(n[i], n[(i + 1) % 3])}];
      if (std::find(n.begin(), n.end(), 1) != n.end()) ++at_ear_corner;
    }
    CHECK(triangles == 4);      // A C B and the three of the ear
    CHECK(at_ear_corner == 2);  // V now has an edge to the centre
    int boundary = 0;
    for (const auto& [edge, uses] : edge_uses) {
      CHECK(uses <= 2);
      boundary += uses == 1;
    }
    CHECK(boundary == 4);  // the outline V A C B is unchanged
    CHECK(cad::split_triangle_ears(d, plane) == 0);
  }
}

TEST_CASE("a volume mesh's boundary ear is split with the tetrahedra on it: same volume, orientation, conforming") {
  // The ear V A B of the test above on face 1 (z = 0) between two solids:
  // tetrahedron 1 (V B A X), X = (0, 0.5, -1), and tetrahedron 3 (V A B Y),
  // Y = (0, 0.5, 1), share it; tetrahedron 2 (A B C X) shares a face with 1.
  io::MshData d;
  add_ear_test_nodes(d, {EntityId{1, 1}, EntityId{1, 1}, EntityId{1, 1}, EntityId{2, 1}});
  for (const auto& [tag, z] : {std::pair{5, -1.0}, std::pair{6, 1.0}}) {
    io::MshNode n;
    n.tag = tag;
    n.x = {0, 0.5, z};
    n.entity = EntityId{3, tag - 4};
    d.nodes.push_back(n);
  }
  add_msh_element(d, 1, 1, 1, {3, 1});
  add_msh_element(d, 1, 1, 1, {1, 2});
  add_msh_element(d, 2, 2, 1, {1, 2, 3});
  add_msh_element(d, 2, 2, 1, {2, 4, 3});
  add_msh_element(d, 4, 3, 1, {1, 3, 2, 5});
  add_msh_element(d, 4, 3, 1, {2, 3, 4, 5});
  add_msh_element(d, 4, 3, 2, {1, 2, 3, 6});
  std::map<std::int64_t, Eigen::Vector3d> at;
  auto signed_volume = [&](std::span<const std::int64_t> n) {
    const Eigen::Vector3d a = at.at(n[0]);
    return (at.at(n[1]) - a).dot((at.at(n[2]) - a).cross(at.at(n[3]) - a)) / 6;
  };
  auto volumes = [&] {  // the signed volume of each solid's tetrahedra, and their number
    for (const auto& n : d.nodes) at[n.tag] = Eigen::Vector3d(n.x[0], n.x[1], n.x[2]);
    std::map<int, std::pair<double, int>> out;
    for (const auto& e : d.elements)
      if (e.type == 4) {
        const double v = signed_volume(d.nodes_of(e));
        CHECK(v > 0.0);  // the input's orientation, every piece
        out[e.entity.tag].first += v;
        ++out[e.entity.tag].second;
      }
    return out;
  };
  const auto before = volumes();
  const cad::FaceGeometry plane{[](int, const Eigen::Vector3d& p) { return Eigen::Vector2d(p.x(), p.y()); },
                                [](int, const Eigen::Vector2d& uv) { return Eigen::Vector3d(uv.x(), uv.y(), 0.0); }};
  CHECK(cad::split_triangle_ears(d, plane) == 1);
  const auto after = volumes();
  CHECK(after.at(1).second == 3 + 1);
  CHECK(after.at(2).second == 3);
  for (int solid : {1, 2}) CHECK(after.at(solid).first == doctest::Approx(before.at(solid).first));
  // Conforming: each triangle of a tetrahedron is shared by at most two, and
  // the outline of the two solids (8 triangles) is unchanged.
  std::map<std::array<std::int64_t, 3>, int> face_uses;
  std::set<std::int64_t> tags;
  for (const auto& e : d.elements) {
    CHECK(tags.insert(e.tag).second);
    if (e.type != 4) continue;
    const auto n = d.nodes_of(e);
    for (int apex = 0; apex < 4; ++apex) {
      std::array<std::int64_t, 3> f{};
      for (int i = 0, k = 0; i < 4; ++i)
        if (i != apex) f[k++] = n[i];
      std::sort(f.begin(), f.end());
      ++face_uses[f];
    }
  }
  int outline = 0;
  for (const auto& [f, uses] : face_uses) {
    CHECK(uses <= 2);
    outline += uses == 1;
  }
  CHECK(outline == 8);
  CHECK(cad::split_triangle_ears(d, plane) == 0);
}

TEST_CASE("a volume ear is kept where the projected centre would invert a piece of its tetrahedron") {
  // The ear V A B (z = 0 here) with tetrahedron V A B Y, Y = (0, 0.5, 1),
  // on a face that the test's geometry bends towards Y: the centre
  // (0, 1/3, 0) projects to (0, 1/3, h). At h = 0.5 every piece keeps its
  // orientation; at h = 2 the centre is past the plane V B Y, so the piece
  // V c B Y would be inverted, and the ear is left as it is.
  for (const auto& [h, ears] : {std::pair{0.5, 1}, std::pair{2.0, 0}}) {
    CAPTURE(h);
    io::MshData d;
    add_ear_test_nodes(d, {EntityId{1, 1}, EntityId{1, 1}, EntityId{1, 1}, EntityId{2, 1}});
    io::MshNode y;
    y.tag = 5;
    y.x = {0, 0.5, 1};
    y.entity = EntityId{3, 1};
    d.nodes.push_back(y);
    add_msh_element(d, 1, 1, 1, {3, 1});
    add_msh_element(d, 1, 1, 1, {1, 2});
    add_msh_element(d, 2, 2, 1, {1, 2, 3});
    add_msh_element(d, 4, 3, 1, {1, 2, 3, 5});
    const double height = h;
    const cad::FaceGeometry bent{[](int, const Eigen::Vector3d& p) { return Eigen::Vector2d(p.x(), p.y()); },
                                 [height](int, const Eigen::Vector2d& uv) {
                                   return Eigen::Vector3d(uv.x(), uv.y(), height * (uv.y() > 0.2));
                                 }};
    const std::size_t nodes = d.nodes.size(), elements = d.elements.size();
    CHECK(cad::split_triangle_ears(d, bent) == ears);
    CHECK(d.nodes.size() == nodes + std::size_t(ears));
    CHECK(d.elements.size() == elements + std::size_t(4 * ears));  // 2 more triangles, 2 more tetrahedra
    for (const auto& e : d.elements)
      if (e.type == 4) {
        std::array<Eigen::Vector3d, 4> x;
        for (int i = 0; i < 4; ++i) {
          const auto& n = *std::find_if(d.nodes.begin(), d.nodes.end(),
                                        [&](const io::MshNode& m) { return m.tag == d.nodes_of(e)[i]; });
          x[i] = Eigen::Vector3d(n.x[0], n.x[1], n.x[2]);
        }
        CHECK((x[1] - x[0]).dot((x[2] - x[0]).cross(x[3] - x[0])) > 0.0);
      }
  }
}

TEST_CASE("a triangle whose corner joins two curves tangentially (G1) is an ear; at a kink it is not") {
  // Face 1 is the plane z = 0. Triangle V A B, V = (0, 0), A = (1, 0.5),
  // B = (-1, 0.5), has edge V-A on curve 1 and edge B-V on curve 2, which
  // meet at model vertex V. Curve 1 leaves V along (1, 0) (the parabola
  // y = x^2 / 2). Curve 2 leaves it along (-1, 0) (the parabola's other
  // half: tangent, an ear), along (-1, 1) (a kink of 135 degrees: not), or
  // along (-1, -0.5) (26.6 degrees off straight, within the 30 degrees of
  // flat_corner_max_angle: an ear). Tangents are given in either sense.
  const std::vector<std::pair<Eigen::Vector3d, int>> cases = {
      {{-1, 0, 0}, 1}, {{1, 0, 0}, 1}, {{-1, 1, 0}, 0}, {{1, -1, 0}, 0}, {{-1, -0.5, 0}, 1}};
  for (const auto& [curve2, ears] : cases) {
    CAPTURE(curve2.transpose());
    io::MshData d;
    add_ear_test_nodes(d, {EntityId{0, 1}, EntityId{1, 1}, EntityId{1, 2}, EntityId{2, 1}});
    add_msh_element(d, 1, 1, 2, {3, 1});
    add_msh_element(d, 1, 1, 1, {1, 2});
    add_msh_element(d, 2, 2, 1, {1, 2, 3});
    add_msh_element(d, 2, 2, 1, {2, 4, 3});
    const cad::FaceGeometry plane{
        [](int, const Eigen::Vector3d& p) { return Eigen::Vector2d(p.x(), p.y()); },
        [](int, const Eigen::Vector2d& uv) { return Eigen::Vector3d(uv.x(), uv.y(), 0.0); },
        [&](int curve, const Eigen::Vector3d& p) -> Eigen::Vector3d {
          REQUIRE(p.norm() == doctest::Approx(0.0));  // asked only at V
          return curve == 1 ? Eigen::Vector3d(2, 0, 0) : Eigen::Vector3d(curve2);
        }};
    CHECK(cad::split_triangle_ears(d, plane) == ears);
    CHECK(d.elements.size() == std::size_t(4 + 2 * ears));
    if (ears == 1) CHECK(cad::split_triangle_ears(d, plane) == 0);
  }
}

TEST_CASE("healing step 4: an edge shorter than merge_small_edges is dropped, its neighbours joined") {
  // A square face of side 10 whose left side is two edges, 9.97 and 0.03 long, nearly in line:
  // wing_fuselage.step's root fairing has such edges (0.036 beside elements of 7 to 14).
  BRepBuilderAPI_MakePolygon polygon;
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {10.0, 0.0}, {10.0, 10.0}, {0.0, 10.0}, {0.001, 0.03}})
    polygon.Add(gp_Pnt(x, y, 0.0));
  polygon.Close();
  const BRepBuilderAPI_MakeFace face(polygon.Wire(), true);
  REQUIRE(face.IsDone());
  const TempDir dir;
  const std::string path = dir / "small_edge.brep";
  REQUIRE(BRepTools::Write(face.Face(), path.c_str()));

  const auto plain = cad::read_cad(path);
  CHECK(plain.num_edges() == 5);
  CHECK(plain.healing().empty());
  cad::CadReadOptions merge;
  merge.merge_small_edges = 0.01;  // shorter than any edge: nothing to do
  CHECK(cad::read_cad(path, merge).num_edges() == 5);
  merge.merge_small_edges = 0.1;
  const auto merged = cad::read_cad(path, merge);
  CHECK(merged.num_edges() == 4);
  CHECK(merged.num_vertices() == 4);
  CHECK(merged.valid());
  REQUIRE(merged.healing().size() == 1);
  CHECK(merged.healing()[0].find("5 -> 4") != std::string::npos);
  // The face is the same face, up to the sliver the dropped edge cut off.
  CHECK(merged.area() == doctest::Approx(plain.area()).epsilon(1e-3));
  double shortest = 1e300;
  for (int e = 1; e <= merged.num_edges(); ++e) shortest = std::min(shortest, merged.curve(e).length());
  CHECK(shortest >= 9.9);
}

TEST_CASE("edge_uv_on_face: the face's point nearest the edge's 3D point, when the pcurve strays from it") {
  // The square [0, 10]^2 in the plane z = 0. Its edge along y = 0 gets a
  // pcurve shifted by 0.3 along the edge: the same segment, S(pcurve(t)) =
  // C(t + 0.3) (as t106_turbine_cascade.step's pcurves stray from their 3D
  // curves, by up to 1.8 at equal parameters).
  BRepBuilderAPI_MakePolygon polygon(gp_Pnt(0, 0, 0), gp_Pnt(10, 0, 0), gp_Pnt(10, 10, 0), gp_Pnt(0, 10, 0), true);
  const BRepBuilderAPI_MakeFace made(polygon.Wire(), true);
  REQUIRE(made.IsDone());
  const TopoDS_Face face = made.Face();
  const Handle(Geom_Surface) plane = BRep_Tool::Surface(face);
  TopoDS_Edge bottom;
  for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
    double a = 0, b = 0;
    const Handle(Geom_Curve) c = BRep_Tool::Curve(TopoDS::Edge(ex.Current()), a, b);
    const gp_Pnt m = c->Value(0.5 * (a + b));
    if (std::abs(m.Y()) < 1e-12) bottom = TopoDS::Edge(ex.Current());
  }
  REQUIRE(!bottom.IsNull());
  double a = 0, b = 0;
  const Handle(Geom_Curve) c3 = BRep_Tool::Curve(bottom, a, b);
  // The straying pcurve: uv(t) = uv of C(t + 0.3), in the plane's own (u, v).
  GeomAPI_ProjectPointOnSurf start(c3->Value(a + 0.3), plane);
  double u0 = 0, v0 = 0;
  start.LowerDistanceParameters(u0, v0);
  GeomAPI_ProjectPointOnSurf next(c3->Value(a + 1.3), plane);
  double u1 = 0, v1 = 0;
  next.LowerDistanceParameters(u1, v1);
  const gp_Dir2d along(u1 - u0, v1 - v0);
  const gp_Pnt2d origin(u0 - a * along.X(), v0 - a * along.Y());
  BRep_Builder().UpdateEdge(bottom, new Geom2d_Line(origin, along), face, 1.0);
  const TempDir dir;
  const std::string path = dir / "stray.brep";
  REQUIRE(BRepTools::Write(face, path.c_str()));

  cad::CadReadOptions as_is;
  as_is.heal = false;  // keep the straying pcurve
  const auto m = cad::read_cad(path, as_is);
  REQUIRE(m.num_faces() == 1);
  int checked = 0;
  for (int e = 1; e <= m.num_edges(); ++e) {
    const auto c = m.curve(e);
    for (int k = 0; k <= 10; ++k) {
      const double t = c.range().lo + 0.1 * k * c.range().length();
      const Eigen::Vector2d uv = m.edge_uv_on_face(e, 1, t);
      CHECK((m.surface(1).evaluate(uv) - c.evaluate(t)).norm() <= 1e-9);
      ++checked;
    }
  }
  CHECK(checked == 44);
  // The pcurve itself does stray: its point is 0.3 along the edge from C(t).
  double pa = 0, pb = 0;
  const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(bottom, face, pa, pb);
  const gp_Pnt2d q = pc->Value(a + 1.0);
  CHECK(plane->Value(q.X(), q.Y()).Distance(c3->Value(a + 1.0)) == doctest::Approx(0.3));
}

namespace {

/// Gmsh's mesh of `m` with its ears kept, as a user's file would give it:
/// nodes and elements only, classified by projection (cad::classify).
template <ElementFamily Family>
Mesh<Family, WarpBlend, 3> unclassified_gmsh_mesh(const CadModel& m, cad::CadMeshOptions o) {
  o.keep_ears = true;
  const auto gmsh = cad::mesh_cad<Family, WarpBlend, 3>(m, o);
  Mesh<Family, WarpBlend, 3> user(1, gmsh.nodes(), gmsh.elements());
  cad::classify(user, m, 1e-7 * m.size());
  return user;
}

/// The number of elements of each entity oriented against the others (the
/// fewer of the two signs): by the signed volume of a tetrahedron; for a
/// surface mesh, its normal at its first corner dotted with its face's at
/// the projection of its centroid (Gmsh orients each face's elements alike;
/// a triangle across a sharp bend of the face can still count as flipped).
template <ElementFamily Family>
std::map<int, int> flipped_elements(const Mesh<Family, WarpBlend, 3>& mesh, const CadModel& m) {
  std::map<int, std::vector<double>> out;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Vector3d a = mesh.node(mesh.vertex(e, 0)), b = mesh.node(mesh.vertex(e, 1));
    // (of a quad: the other neighbour of corner 0)
    const Eigen::Vector3d c = mesh.node(mesh.vertex(e, Family::is_simplex ? 2 : 3));
    const int entity = mesh.element_entities()[e];
    if constexpr (Family::dim == 3) {
      out[entity].push_back((b - a).dot((c - a).cross(Eigen::Vector3d(mesh.node(mesh.vertex(e, 3))) - a)));
    } else {
      const auto s = m.surface(entity);
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int k = 0; k < Family::num_vertices; ++k) centroid += mesh.node(mesh.vertex(e, k)) / Family::num_vertices;
      const auto d = s.derivatives(s.project(centroid));
      out[entity].push_back((b - a).cross(c - a).dot(d.col(0).cross(d.col(1))));
    }
  }
  std::map<int, int> flipped;
  for (const auto& [entity, signs] : out) {
    const auto positive = std::count_if(signs.begin(), signs.end(), [](double v) { return v > 0.0; });
    flipped[entity] = int(std::min<std::ptrdiff_t>(positive, std::ssize(signs) - positive));
  }
  return flipped;
}

}  // namespace

TEST_CASE_TEMPLATE("a user's linear mesh, classified by projection, gets the ears Gmsh's lines would split",
                   Family, Simplex<3>, Simplex<2>, Cube<2>) {
  // A prism on a thin ellipse (semi-axes 1 and 0.08): at each sharp end of
  // the ellipse the coarse mesh of a cap has an element with two edges on it.
  const TempDir dir;
  const std::string path = dir / "thin_prism.brep";
  const gp_Elips ellipse(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 1.0, 0.08);
  const BRepBuilderAPI_MakeFace cap(BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(ellipse).Edge()).Wire(), true);
  REQUIRE(cap.IsDone());
  REQUIRE(BRepTools::Write(BRepPrimAPI_MakePrism(cap.Face(), gp_Vec(0, 0, 0.5)).Shape(), path.c_str()));
  const auto m = cad::read_cad(path);
  REQUIRE(m.num_solids() == 1);
  int sizes_with_ears = 0;
  for (double size : {0.2, 0.3, 0.5}) {
    CAPTURE(size);
    cad::CadMeshOptions o;
    o.size = size;
    auto mesh = unclassified_gmsh_mesh<Family>(m, o);
    const int nodes = mesh.num_nodes(), elements = mesh.num_elements();
    const auto flipped_before = flipped_elements(mesh, m);
    const int ears = cad::split_mesh_ears(mesh, m);
    // The reference: Gmsh's mesh split through its own curve lines.
    const auto split_by_gmsh = cad::mesh_cad<Family, WarpBlend, 3>(m, o);
    CHECK(mesh.num_elements() == split_by_gmsh.num_elements());
    CHECK(mesh.num_nodes() == split_by_gmsh.num_nodes());
    const int nodes_per_ear = Family::is_simplex ? 1 : 4, elements_per_ear = Family::is_simplex ? 2 : 4;
    CHECK(mesh.num_nodes() == nodes + nodes_per_ear * ears);
    CHECK(mesh.num_elements() >= elements + elements_per_ear * ears);
    if (ears == 0) continue;
    ++sizes_with_ears;
    cad::classify(mesh, m, 1e-7 * m.size());  // the new nodes lie on the model
    CHECK(flipped_elements(mesh, m) == flipped_before);
    CHECK(cad::split_mesh_ears(mesh, m) == 0);
  }
  CHECK(sizes_with_ears > 0);
}

namespace {

/// A planar mesh classified on the model as hom::tools::classify_user_mesh
/// does: lifted to z = 0, classified as a surface mesh, copied back.
template <ElementFamily Family>
void classify_planar(Mesh<Family, WarpBlend, 2>& mesh, const CadModel& m) {
  typename Mesh<Family, WarpBlend, 3>::Coordinates lifted_nodes = Eigen::Matrix3Xd::Zero(3, mesh.num_nodes());
  lifted_nodes.topRows(2) = mesh.nodes();
  Mesh<Family, WarpBlend, 3> lifted(1, lifted_nodes, mesh.elements());
  cad::classify(lifted, m, 1e-7 * m.size());
  mesh.node_classes() = lifted.node_classes();
  mesh.element_entities() = lifted.element_entities();
  mesh.entities() = lifted.entities();
}

/// Twice the signed area of each quadrilateral (its four corners).
std::vector<double> signed_areas(const Mesh<Cube<2>, WarpBlend, 2>& mesh) {
  std::vector<double> out;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    double twice = 0.0;
    for (int k = 0; k < 4; ++k) {  // corners 0 to 3 go around the quadrilateral (Cube<2>::vertex_corner)
      const Eigen::Vector2d a = mesh.node(mesh.vertex(e, k)), b = mesh.node(mesh.vertex(e, (k + 1) % 4));
      twice += a.x() * b.y() - a.y() * b.x();
    }
    out.push_back(twice);
  }
  return out;
}

}  // namespace

TEST_CASE("a user's planar quadrilateral mesh gets its ears split in the plane, as Gmsh's lines would") {
  // The thin ellipse alone (semi-axes 1 and 0.08): a planar model in z = 0.
  const TempDir dir;
  const std::string path = dir / "thin_ellipse.brep";
  const gp_Elips ellipse(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 1.0, 0.08);
  const BRepBuilderAPI_MakeFace face(BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(ellipse).Edge()).Wire(), true);
  REQUIRE(face.IsDone());
  REQUIRE(BRepTools::Write(face.Face(), path.c_str()));
  const auto m = cad::read_cad(path);
  REQUIRE(m.num_faces() == 1);
  cad::CadMeshOptions o;
  o.size = 0.3;
  cad::CadMeshOptions kept = o;
  kept.keep_ears = true;
  const auto gmsh = cad::mesh_cad<Cube<2>, WarpBlend, 2>(m, kept);
  Mesh<Cube<2>, WarpBlend, 2> mesh(1, gmsh.nodes(), gmsh.elements());
  classify_planar(mesh, m);
  const int nodes = mesh.num_nodes(), elements = mesh.num_elements();
  const int ears = cad::split_mesh_ears(mesh, m);
  REQUIRE(ears > 0);
  // The reference: Gmsh's mesh split through its own curve lines.
  const auto split_by_gmsh = cad::mesh_cad<Cube<2>, WarpBlend, 2>(m, o);
  CHECK(mesh.num_elements() == split_by_gmsh.num_elements());
  CHECK(mesh.num_nodes() == split_by_gmsh.num_nodes());
  CHECK(mesh.num_nodes() == nodes + 4 * ears);
  CHECK(mesh.num_elements() == elements + 4 * ears);
  // Every quadrilateral is turned as Gmsh's are; the new nodes lie inside the
  // ellipse, near its sharp ends (x = -1 and 1), at both.
  const auto areas = signed_areas(mesh);
  CHECK(std::all_of(areas.begin(), areas.end(), [&](double a) { return a * areas.front() > 0.0; }));
  bool left = false, right = false;
  for (int i = nodes; i < mesh.num_nodes(); ++i) {
    const Eigen::Vector2d x = mesh.node(i);
    CHECK(x.x() * x.x() + x.y() * x.y() / (0.08 * 0.08) < 1.0);
    CHECK(std::abs(x.x()) > 0.7);
    (x.x() < 0 ? left : right) = true;
  }
  CHECK((left && right));
  classify_planar(mesh, m);
  CHECK(cad::split_mesh_ears(mesh, m) == 0);
  // Planar triangles (Gmsh's, ears kept) are left to the curving pipeline's flat-corner split.
  const auto gmsh_triangles = cad::mesh_cad<Simplex<2>, WarpBlend, 2>(m, kept);
  Mesh<Simplex<2>, WarpBlend, 2> triangles(1, gmsh_triangles.nodes(), gmsh_triangles.elements());
  classify_planar(triangles, m);
  CHECK(cad::split_mesh_ears(triangles, m) == 0);
  CHECK(triangles.num_elements() == gmsh_triangles.num_elements());
}

TEST_CASE("real CAD files from ../shared/data/cad (skipped when absent)") {
  const auto dir = shared_cad_dir();
  if (!std::filesystem::exists(dir / "README.md")) {
    MESSAGE("no " << dir.string() << ": skipped");
    return;
  }
  struct Expect {
    const char* file;
    int solids, faces;
  };
  for (const Expect& x : {Expect{"wing_fuselage.step", 2, 16}, Expect{"spur_gear_10t.step", 1, 128},
                          Expect{"ring_in_sphere.brep", 2, 13}, Expect{"gear_face_2d.brep", 0, 1},
                          Expect{"t106_turbine_cascade.step", 0, 8}}) {
    CAPTURE(x.file);
    const auto m = cad::read_cad((dir / x.file).string());
    CHECK(m.num_solids() == x.solids);
    CHECK(m.num_faces() == x.faces);
    // Every face's surface passes through its own sample points.
    std::mt19937 rng(2);
    for (int f = 1; f <= m.num_faces(); ++f) {
      const auto s = m.surface(f);
      const Eigen::Vector2d uv = random_uv(s, rng, 0.1);
      CHECK((s.evaluate(s.project(s.evaluate(uv))) - s.evaluate(uv)).norm() <= 1e-7 * m.size());
    }
  }
  // The root fairing's two 0.036 edges go with healing step 4; the model stays valid.
  cad::CadReadOptions merge;
  merge.merge_small_edges = 0.05;
  const auto wing = cad::read_cad((dir / "wing_fuselage.step").string());
  const auto merged = cad::read_cad((dir / "wing_fuselage.step").string(), merge);
  CHECK(merged.num_edges() == wing.num_edges() - 2);
  CHECK(merged.num_faces() == wing.num_faces());
  CHECK(merged.valid());
  // Joining the neighbours at one vertex moves the faces there by about the dropped edge's length.
  CHECK(merged.volume() == doctest::Approx(wing.volume()).epsilon(1e-4));
  // Frontal-Delaunay lays slivers across the root fairing's collapsed B-spline patches (faces 3 and 14);
  // cad_mesh_data meshes those again with MeshAdapt, at the size.
  cad::CadMeshOptions fairing;
  fairing.size_from_curvature = 8;
  fairing.size_min = 14;
  std::vector<std::string> notes;
  fairing.progress = [&](const std::string& line) { notes.push_back(line); };
  auto longest_edge = [](const auto& mesh) {
    double longest = 0;
    for (int e = 0; e < mesh.num_elements(); ++e)
      for (int i = 0; i < 3; ++i)
        longest = std::max(longest, (mesh.node(mesh.vertex(e, i)) - mesh.node(mesh.vertex(e, (i + 1) % 3))).norm());
    return longest;
  };
  const double size = cad::default_mesh_size(wing);
  CHECK(longest_edge(cad::mesh_cad<Simplex<2>, WarpBlend, 3>(wing, fairing)) < 2 * size);
  REQUIRE(notes.size() == 1);
  CHECK(notes[0].find("faces 3 14 meshed again with MeshAdapt") != std::string::npos);
  fairing.algorithm_2d = 6;  // Frontal-Delaunay everywhere, as asked: the slivers stay
  CHECK(longest_edge(cad::mesh_cad<Simplex<2>, WarpBlend, 3>(wing, fairing)) > 2 * size);
  CHECK(notes.size() == 1);
  // t106's elements up to 94 long at size 46 have angles of 10 degrees: stretched, no slivers, kept.
  const auto cascade = cad::read_cad((dir / "t106_turbine_cascade.step").string());
  cad::CadMeshOptions blade;
  blade.size_from_curvature = 24;
  blade.progress = fairing.progress;
  const auto cascade_mesh = cad::mesh_cad<Simplex<2>, WarpBlend, 3>(cascade, blade);
  CHECK(longest_edge(cascade_mesh) > 2 * cad::default_mesh_size(cascade));
  CHECK(notes.size() == 1);
  const auto sphere = cad::read_cad((dir / "sphere_nurbs_8patch_rhino.igs").string());
  CHECK(sphere.num_faces() >= 1);
  for (int f = 1; f <= sphere.num_faces(); ++f) {
    std::mt19937 rng(4);
    const auto s = sphere.surface(f);
    for (int i = 0; i < 10; ++i) CHECK(s.evaluate(random_uv(s, rng)).norm() == doctest::Approx(1.0).epsilon(1e-6));
  }
}
