// OpenCASCADE models built in code for chapter 6's cases (curve_models.hpp).

#include "curve_models.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeEdge.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeWire.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepFilletAPI_MakeFillet2d.hxx>
#include <BRepOffsetAPI_ThruSections.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRep_Tool.hxx>
#include <GC_MakeArcOfCircle.hxx>
#include <GeomAPI_Interpolate.hxx>
#include <Standard_Failure.hxx>
#include <TColgp_HArray1OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax2.hxx>
#include <gp_Circ.hxx>
#include <gp_Elips.hxx>
#include <gp_Pnt.hxx>
#include <gp_Trsf.hxx>
#include <gp_Vec.hxx>

#include "occ_data.hpp"

namespace hom::cad {

namespace {

constexpr double pi = std::numbers::pi;

TopoDS_Wire circle_wire(double x, double y, double r) {
  const gp_Circ c(gp_Ax2(gp_Pnt(x, y, 0), gp::DZ()), r);
  return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(c).Edge()).Wire();
}

TopoDS_Face disk(double x, double y, double r) { return BRepBuilderAPI_MakeFace(circle_wire(x, y, r), true).Face(); }

// The face of `shape` (a boolean on faces returns a compound of one face).
TopoDS_Face single_face(const TopoDS_Shape& shape, const char* what) {
  TopExp_Explorer ex(shape, TopAbs_FACE);
  if (!ex.More()) throw std::runtime_error(std::string("hom::cad: ") + what + ": no face");
  TopoDS_Face f = TopoDS::Face(ex.Current());
  ex.Next();
  if (ex.More()) throw std::runtime_error(std::string("hom::cad: ") + what + ": more than one face");
  return f;
}

// The NACA 00tt profile of chord `chord` with its leading edge at (x0, 0, z):
// two B-splines through points of its upper and lower sides (cosine spacing,
// denser at both edges) that meet at the leading edge and at the closed, sharp
// trailing edge. Two edges, not one closed curve: a loft through them has the
// trailing edge as an edge between two faces, not as the seam of one closed
// surface whose two sides meet at a crease.
TopoDS_Wire naca_section(double thickness, double chord, double x0, double z) {
  const int per_side = 40;
  auto half_thickness = [thickness](double x) {  // NACA four-digit series, closed trailing edge
    return 5 * thickness *
           (0.2969 * std::sqrt(x) - 0.1260 * x - 0.3516 * x * x + 0.2843 * x * x * x - 0.1036 * x * x * x * x);
  };
  auto side = [&](double sign) {  // trailing edge to leading edge (upper), or back (lower)
    Handle(TColgp_HArray1OfPnt) pts = new TColgp_HArray1OfPnt(1, per_side + 1);
    for (int i = 0; i <= per_side; ++i) {
      const int k = sign > 0 ? i : per_side - i;
      const double x = 0.5 * (1 + std::cos(pi * k / per_side));
      pts->SetValue(i + 1, gp_Pnt(x0 + chord * x, sign * chord * half_thickness(x), z));
    }
    GeomAPI_Interpolate interp(pts, /*periodic=*/false, 1e-9);
    interp.Perform();
    if (!interp.IsDone()) throw std::runtime_error("hom::cad: the NACA section's interpolation failed");
    return BRepBuilderAPI_MakeEdge(interp.Curve()).Edge();
  };
  return BRepBuilderAPI_MakeWire(side(1.0), side(-1.0)).Wire();
}

template <class F>
CadModel built(const std::string& name, F&& make) {
  try {
    return detail::make_model(name, make());
  } catch (const Standard_Failure& e) {
    throw std::runtime_error("hom::cad: OpenCASCADE failed to build " + name + " (" +
                             std::string(e.GetMessageString() ? e.GetMessageString() : "no message") + ")");
  }
}

}  // namespace

CadModel plate_with_holes_model() {
  return built("plate_with_holes", [] {
    // The L outline, counter-clockwise (normal +z).
    const std::vector<gp_Pnt> outline = {{0, 0, 0}, {10, 0, 0}, {10, 4, 0}, {5, 4, 0}, {5, 8, 0}, {0, 8, 0}};
    BRepBuilderAPI_MakePolygon poly;
    for (const auto& p : outline) poly.Add(p);
    poly.Close();
    const TopoDS_Face plate = BRepBuilderAPI_MakeFace(poly.Wire(), true).Face();
    BRepFilletAPI_MakeFillet2d fillet(plate);
    TopTools_IndexedMapOfShape vertices;
    TopExp::MapShapes(plate, TopAbs_VERTEX, vertices);
    for (int i = 1; i <= vertices.Extent(); ++i) {
      const TopoDS_Vertex& v = TopoDS::Vertex(vertices(i));
      const gp_Pnt p = BRep_Tool::Pnt(v);
      const bool reentrant = p.Distance(gp_Pnt(5, 4, 0)) < 1e-9;
      fillet.AddFillet(v, reentrant ? 0.8 : 1.0);
    }
    fillet.Build();
    if (!fillet.IsDone()) throw std::runtime_error("hom::cad::plate_with_holes_model: the fillets failed");
    TopoDS_Shape part = fillet.Shape();
    // A stadium-shaped slot: two lines and two half circles.
    BRepBuilderAPI_MakeWire slot;
    slot.Add(BRepBuilderAPI_MakeEdge(gp_Pnt(4.5, 1.6, 0), gp_Pnt(5.5, 1.6, 0)).Edge());
    slot.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(gp_Pnt(5.5, 1.6, 0), gp_Pnt(5.9, 2.0, 0), gp_Pnt(5.5, 2.4, 0)).Value()).Edge());
    slot.Add(BRepBuilderAPI_MakeEdge(gp_Pnt(5.5, 2.4, 0), gp_Pnt(4.5, 2.4, 0)).Edge());
    slot.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(gp_Pnt(4.5, 2.4, 0), gp_Pnt(4.1, 2.0, 0), gp_Pnt(4.5, 1.6, 0)).Value()).Edge());
    const TopoDS_Face slot_face = BRepBuilderAPI_MakeFace(slot.Wire(), true).Face();
    for (const TopoDS_Face& hole : {disk(1.8, 1.8, 0.7), disk(8.3, 2.0, 0.9), disk(2.5, 6.2, 0.8), slot_face}) {
      BRepAlgoAPI_Cut cut(part, hole);
      if (!cut.IsDone()) throw std::runtime_error("hom::cad::plate_with_holes_model: cutting a hole failed");
      part = single_face(cut.Shape(), "plate_with_holes_model");
    }
    return part;
  });
}

CadModel gear_model(int teeth, double radius, double thickness) {
  if (teeth < 3 || !(radius > 0) || !(thickness > 0))
    throw std::invalid_argument("hom::cad::gear_model: need >= 3 teeth, positive radius and thickness");
  return built("gear", [&] {
    // Radius of the profile at pitch fraction tau in [0, 1): tip plateau
    // |tau - 1/2| < 0.15, root beyond 0.33, smoothstep flanks between (they
    // widen towards the root like involute flanks, with rounded tip and root).
    const double h = 0.2 * radius, root = radius - h;
    auto profile = [&](double tau) {
      const double d = std::abs(tau - 0.5), dt = 0.15, dr = 0.33;
      if (d <= dt) return radius;
      if (d >= dr) return root;
      const double s = (dr - d) / (dr - dt);
      return root + h * s * s * (3 - 2 * s);
    };
    const int per_tooth = 24, n = teeth * per_tooth;
    Handle(TColgp_HArray1OfPnt) pts = new TColgp_HArray1OfPnt(1, n);
    for (int i = 0; i < n; ++i) {
      const double theta = 2 * pi * i / n;
      const double r = profile(double(i % per_tooth) / per_tooth);
      pts->SetValue(i + 1, gp_Pnt(r * std::cos(theta), r * std::sin(theta), 0));
    }
    GeomAPI_Interpolate interp(pts, /*periodic=*/true, 1e-9);
    interp.Perform();
    if (!interp.IsDone()) throw std::runtime_error("hom::cad::gear_model: the profile interpolation failed");
    const TopoDS_Wire outer = BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(interp.Curve()).Edge()).Wire();
    const TopoDS_Face wheel = BRepBuilderAPI_MakeFace(outer, true).Face();
    BRepAlgoAPI_Cut bore(wheel, disk(0, 0, 0.3 * radius));
    if (!bore.IsDone()) throw std::runtime_error("hom::cad::gear_model: cutting the bore failed");
    const TopoDS_Face section = single_face(bore.Shape(), "gear_model");
    BRepPrimAPI_MakePrism prism(section, gp_Vec(0, 0, thickness));
    if (!prism.IsDone()) throw std::runtime_error("hom::cad::gear_model: the extrusion failed");
    return prism.Shape();
  });
}

CadModel propeller_model(int blades) {
  if (blades < 2) throw std::invalid_argument("hom::cad::propeller_model: need >= 2 blades");
  return built("propeller", [&] {
    const double hub_radius = 0.3, hub_length = 0.6;
    TopoDS_Shape part =
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -0.5 * hub_length), gp::DZ()), hub_radius, hub_length).Shape();
    // Blade sections along +x: radius, chord, pitch angle (degrees from the
    // hub's plane). The first lies inside the hub, so that the fuse cuts the
    // blade's root on the cylinder.
    struct Section {
      double radius, chord, pitch;
    };
    const Section sections[] = {{0.15, 0.50, 60}, {0.6, 0.46, 45}, {1.0, 0.36, 32}, {1.3, 0.22, 24}};
    BRepOffsetAPI_ThruSections loft(/*isSolid=*/true, /*ruled=*/false);
    loft.CheckCompatibility(false);  // one elliptic edge per section, seams aligned by construction
    for (const Section& s : sections) {
      const double b = s.pitch * pi / 180;
      const gp_Dir chord_direction(0, std::cos(b), std::sin(b));
      const gp_Elips e(gp_Ax2(gp_Pnt(s.radius, 0, 0), gp::DX(), chord_direction), 0.5 * s.chord, 0.09 * s.chord);
      loft.AddWire(BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(e).Edge()).Wire());
    }
    loft.Build();
    if (!loft.IsDone()) throw std::runtime_error("hom::cad::propeller_model: the blade loft failed");
    const TopoDS_Shape blade = loft.Shape();
    for (int k = 0; k < blades; ++k) {
      gp_Trsf turn;
      turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp::DZ()), 2 * pi * k / blades);
      BRepAlgoAPI_Fuse fuse(part, BRepBuilderAPI_Transform(blade, turn, true).Shape());
      if (!fuse.IsDone()) throw std::runtime_error("hom::cad::propeller_model: fusing a blade to the hub failed");
      part = fuse.Shape();
    }
    return part;
  });
}

CadModel wing_domain_model(double thickness) {
  if (!(thickness > 0 && thickness < 0.5))
    throw std::invalid_argument("hom::cad::wing_domain_model: thickness in (0, 0.5)");
  return built("wing_domain", [&] {
    BRepOffsetAPI_ThruSections loft(/*isSolid=*/true, /*ruled=*/false);
    loft.AddWire(naca_section(thickness, 1.0, 0.0, 0.0));  // root, on the symmetry plane
    loft.AddWire(naca_section(thickness, 0.6, 0.3, 1.5));  // tip: taper 0.6, leading edge swept back 0.3
    loft.Build();
    if (!loft.IsDone()) throw std::runtime_error("hom::cad::wing_domain_model: the wing loft failed");
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(-1.5, -1.5, 0), gp_Pnt(3.0, 1.5, 2.5)).Shape();
    BRepAlgoAPI_Cut cut(box, loft.Shape());
    if (!cut.IsDone()) throw std::runtime_error("hom::cad::wing_domain_model: cutting the wing from the box failed");
    return cut.Shape();
  });
}

CadModel cone_model(double radius, double height) {
  if (!(radius > 0.0) || !(height > 0.0))
    throw std::invalid_argument("hom::cad::cone_model: radius and height must be > 0");
  return built("cone", [&] { return BRepPrimAPI_MakeCone(gp_Ax2(gp::Origin(), gp::DZ()), radius, 0.0, height).Shape(); });
}

std::optional<PlanarPlacement> place_in_xy_plane(const CadModel& cad, double tolerance) {
  if (cad.num_faces() == 0) return std::nullopt;
  const double scale = std::max(cad.size(), 1e-300);
  Eigen::Vector3d p0 = Eigen::Vector3d::Zero(), n0 = Eigen::Vector3d::UnitZ();
  for (int f = 1; f <= cad.num_faces(); ++f) {
    const auto s = cad.surface(f);
    if (s.type() != "plane") return std::nullopt;
    const Eigen::Vector2d uv(0.5 * (s.range(0).lo + s.range(0).hi), 0.5 * (s.range(1).lo + s.range(1).hi));
    const auto d = s.derivatives(uv);
    Eigen::Vector3d n = d.col(0).cross(d.col(1)).normalized();
    if (s.reversed()) n = -n;
    const Eigen::Vector3d p = s.evaluate(uv);
    if (f == 1) {
      p0 = p;
      n0 = n;
    } else if (std::abs(std::abs(n.dot(n0)) - 1.0) > tolerance || std::abs((p - p0).dot(n0)) > tolerance * scale) {
      return std::nullopt;
    }
  }
  PlanarPlacement out{cad};
  // Rotation taking n0 to +z (Rodrigues), unless the plane is already
  // parallel to z = 0.
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d axis = n0.cross(ez);
  if (axis.norm() > tolerance) {
    const double angle = std::atan2(axis.norm(), n0.dot(ez));
    out.rotation = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  }
  out.translation = -(out.rotation * p0).dot(ez) * ez;
  if (axis.norm() <= tolerance && out.translation.norm() <= tolerance * scale) return out;
  out.moved = true;
  gp_Trsf t;
  const auto& R = out.rotation;
  const auto& c = out.translation;
  t.SetValues(R(0, 0), R(0, 1), R(0, 2), c[0], R(1, 0), R(1, 1), R(1, 2), c[1], R(2, 0), R(2, 1), R(2, 2), c[2]);
  out.model = built(cad.name(), [&] { return BRepBuilderAPI_Transform(cad.data().shape, t, true).Shape(); });
  return out;
}

}  // namespace hom::cad
