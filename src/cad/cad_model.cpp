// CAD models: reading STEP/IGES/BREP with OpenCASCADE, healing, indexing,
// writing, and the built-in models (cad_model.hpp).

#include "cad_model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBndLib.hxx>
#include <BRepClass3d.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeSolid.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <GeomAdaptor_Curve.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Curve.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_SphericalSurface.hxx>
#include <Geom2d_Curve.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <ShapeExtend_Status.hxx>
#include <ShapeFix_Shape.hxx>
#include <ShapeFix_Solid.hxx>
#include <ShapeFix_Wireframe.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt.hxx>
#include <gp_Sphere.hxx>

#include "hom/detail/surface_projection.hpp"
#include "occ_data.hpp"

namespace hom::cad {

namespace {

// Silences OpenCASCADE's default messenger (the readers' and writers'
// statistics and warnings on stdout) for its lifetime; errors reach the
// caller as CadError.
class QuietOcc {
 public:
  QuietOcc() {
    for (Message_SequenceOfPrinters::Iterator it(Message::DefaultMessenger()->Printers()); it.More(); it.Next()) {
      saved_.emplace_back(it.Value(), it.Value()->GetTraceLevel());
      it.Value()->SetTraceLevel(Message_Fail);
    }
  }
  ~QuietOcc() {
    for (auto& [printer, level] : saved_) printer->SetTraceLevel(level);
  }
  QuietOcc(const QuietOcc&) = delete;
  QuietOcc& operator=(const QuietOcc&) = delete;

 private:
  std::vector<std::pair<Handle(Message_Printer), Message_Gravity>> saved_;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string failure_text(const Standard_Failure& e) {
  const char* m = e.GetMessageString();
  return std::string(e.DynamicType()->Name()) + (m && *m ? std::string(": ") + m : std::string());
}

int count(const TopoDS_Shape& s, TopAbs_ShapeEnum what) {
  TopTools_IndexedMapOfShape m;
  if (!s.IsNull()) TopExp::MapShapes(s, what, m);
  return m.Extent();
}

double diagonal(const TopoDS_Shape& s) {
  Bnd_Box box;
  BRepBndLib::Add(s, box);
  return box.IsVoid() ? 0.0 : std::sqrt(box.SquareExtent());
}

// Edges that bound exactly one face (not seams, not degenerated).
int free_edges(const TopoDS_Shape& s) {
  TopTools_IndexedDataMapOfShapeListOfShape m;
  TopExp::MapShapesAndAncestors(s, TopAbs_EDGE, TopAbs_FACE, m);
  int n = 0;
  for (int i = 1; i <= m.Extent(); ++i) {
    const TopoDS_Edge& e = TopoDS::Edge(m.FindKey(i));
    if (BRep_Tool::Degenerated(e)) continue;
    TopTools_IndexedMapOfShape faces;
    for (const auto& f : m.FindFromIndex(i)) faces.Add(f);
    if (faces.Extent() == 1 && !BRep_Tool::IsClosed(e, TopoDS::Face(faces(1)))) ++n;
  }
  return n;
}

// The healing steps of cad_model.hpp; returns what changed.
TopoDS_Shape heal(TopoDS_Shape shape, const CadReadOptions& o, std::vector<std::string>& log) {
  // ShapeFix only where OpenCASCADE's checker finds a fault: on valid
  // shapes it can still retouch tolerances and pcurves, and Gmsh 4.8.4 then
  // fails to mesh some models it meshes as read (ring_in_sphere.brep).
  if (o.heal && !BRepCheck_Analyzer(shape).IsValid()) {
    Handle(ShapeFix_Shape) fix = new ShapeFix_Shape(shape);
    fix->Perform();
    if (fix->Status(ShapeExtend_DONE)) {
      std::string what;
      const char* names[] = {"edges", "wires", "faces", "shells", "solids", "compounds"};
      const ShapeExtend_Status done[] = {ShapeExtend_DONE1, ShapeExtend_DONE2, ShapeExtend_DONE3,
                                         ShapeExtend_DONE4, ShapeExtend_DONE5, ShapeExtend_DONE6};
      for (int k = 0; k < 6; ++k)
        if (fix->Status(done[k])) what += (what.empty() ? "" : ", ") + std::string(names[k]);
      log.push_back("invalid shape (BRepCheck_Analyzer): ShapeFix_Shape fixed " +
                    (what.empty() ? std::string("the shape") : what));
      shape = fix->Shape();
    }
  }
  if (o.sew && count(shape, TopAbs_FACE) > 1) {
    const int before = free_edges(shape);
    if (before > 0) {
      BRepBuilderAPI_Sewing sew(1e-6 * std::max(diagonal(shape), 1e-300));
      sew.Add(shape);
      sew.Perform();
      const TopoDS_Shape sewn = sew.SewedShape();
      if (!sewn.IsNull()) {
        const int after = free_edges(sewn);
        if (after < before) {
          log.push_back("sewing joined faces: free edges " + std::to_string(before) + " -> " + std::to_string(after));
          shape = sewn;
        }
      }
    }
  }
  if (o.make_solids && count(shape, TopAbs_SOLID) == 0) {
    std::vector<TopoDS_Shell> closed;
    for (TopExp_Explorer ex(shape, TopAbs_SHELL); ex.More(); ex.Next())
      if (BRep_Tool::IsClosed(ex.Current())) closed.push_back(TopoDS::Shell(ex.Current()));
    if (!closed.empty()) {
      BRep_Builder b;
      TopoDS_Compound c;
      b.MakeCompound(c);
      ShapeFix_Solid fix;
      for (const auto& sh : closed) b.Add(c, fix.SolidFromShell(sh));
      // Keep whatever else the shape holds (faces outside the closed shells).
      TopTools_IndexedMapOfShape in_solids;
      TopExp::MapShapes(c, TopAbs_FACE, in_solids);
      for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next())
        if (!in_solids.Contains(ex.Current())) b.Add(c, ex.Current());
      log.push_back(std::to_string(closed.size()) + " closed shell" + (closed.size() > 1 ? "s" : "") + " made solid");
      shape = c;
    }
  }
  if (o.merge_small_edges > 0.0) {
    const int before = count(shape, TopAbs_EDGE);
    ShapeFix_Wireframe fix(shape);
    fix.SetPrecision(o.merge_small_edges);
    // Without drop mode FixSmallEdges only merges an edge whose neighbours meet it within the
    // limit angle and leaves wing_fuselage's 0.036 edges alone; drop mode removes each small
    // edge and joins its neighbours at one vertex (as Gmsh's Geometry.OCCFixSmallEdges does).
    fix.ModeDropSmallEdges() = Standard_True;
    if (fix.FixSmallEdges()) {
      const TopoDS_Shape merged = fix.Shape();
      log.push_back("small edges (shorter than " + std::to_string(o.merge_small_edges) + ") dropped: edges " +
                    std::to_string(before) + " -> " + std::to_string(count(merged, TopAbs_EDGE)));
      shape = merged;
    }
  }
  return shape;
}

template <class Reader>
TopoDS_Shape transfer(Reader& reader, const std::string& path, const char* kind) {
  const IFSelect_ReturnStatus st = reader.ReadFile(path.c_str());
  if (st != IFSelect_RetDone)
    throw CadError(path + ": not a readable " + kind + " file (OpenCASCADE reader status " + std::to_string(int(st)) + ")");
  if (reader.TransferRoots() <= 0 && reader.NbShapes() == 0)
    throw CadError(path + ": the " + kind + " file has no shape OpenCASCADE can transfer (no supported geometric entity)");
  return reader.OneShape();
}

TopoDS_Shape read_shape(const std::string& path) {
  switch (cad_format(path)) {
    case CadFormat::step: {
      STEPControl_Reader r;
      return transfer(r, path, "STEP");
    }
    case CadFormat::iges: {
      IGESControl_Controller::Init();
      IGESControl_Reader r;
      return transfer(r, path, "IGES");
    }
    case CadFormat::brep: {
      TopoDS_Shape s;
      BRep_Builder b;
      if (!BRepTools::Read(s, path.c_str(), b)) throw CadError(path + ": not a readable BREP file");
      return s;
    }
  }
  return {};
}

std::string plural(int n, const std::string& one, const std::string& many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// Writes with `write(tmp)` to a temporary of the same extension, then renames.
template <class F>
void write_via_temporary(const std::string& path, F&& write) {
  const std::filesystem::path p(path);
  const std::string tmp = (p.parent_path() / (p.stem().string() + ".tmp" + p.extension().string())).string();
  bool ok = false;
  const QuietOcc quiet;
  try {
    ok = write(tmp);
  } catch (const Standard_Failure& e) {
    std::remove(tmp.c_str());
    throw CadError(path + ": OpenCASCADE failed to write (" + failure_text(e) + ")");
  }
  if (!ok) {
    std::remove(tmp.c_str());
    throw CadError(path + ": cannot write");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw CadError(path + ": cannot rename " + tmp + " (" + ec.message() + ")");
  }
}

int check_tag(const TopTools_IndexedMapOfShape& m, int tag, const char* what) {
  if (tag < 1 || tag > m.Extent())
    throw std::out_of_range(std::string("hom::cad::CadModel: no ") + what + " " + std::to_string(tag) + " (model has " +
                            std::to_string(m.Extent()) + ")");
  return tag;
}

}  // namespace

CadFormat cad_format(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext == ".step" || ext == ".stp") return CadFormat::step;
  if (ext == ".iges" || ext == ".igs") return CadFormat::iges;
  if (ext == ".brep" || ext == ".brp") return CadFormat::brep;
  throw CadError(path + ": unsupported CAD file extension '" + ext + "' (use .step/.stp, .iges/.igs or .brep)");
}

namespace detail {

CadModel make_model(std::string name, const TopoDS_Shape& shape, std::vector<std::string> healing) {
  auto d = std::make_shared<CadModelData>();
  d->name = std::move(name);
  d->shape = shape;
  d->healing = std::move(healing);
  TopExp::MapShapes(shape, TopAbs_SOLID, d->solids);
  TopExp::MapShapes(shape, TopAbs_SHELL, d->shells);
  TopExp::MapShapes(shape, TopAbs_FACE, d->faces);
  TopExp::MapShapes(shape, TopAbs_EDGE, d->edges);
  TopExp::MapShapes(shape, TopAbs_VERTEX, d->vertices);
  for (int i = 1; i <= d->faces.Extent(); ++i) d->surfaces.push_back(make_surface_data(TopoDS::Face(d->faces(i))));
  for (int i = 1; i <= d->edges.Extent(); ++i) d->curves.push_back(make_curve_data(TopoDS::Edge(d->edges(i))));
  return CadModel(std::move(d));
}

}  // namespace detail

CadModel::CadModel() : data_(std::make_shared<detail::CadModelData>()) {}
CadModel::CadModel(std::shared_ptr<const detail::CadModelData> data) : data_(std::move(data)) {}

const std::string& CadModel::name() const { return data_->name; }
int CadModel::num_solids() const { return data_->solids.Extent(); }
int CadModel::num_shells() const { return data_->shells.Extent(); }
int CadModel::num_faces() const { return data_->faces.Extent(); }
int CadModel::num_edges() const { return data_->edges.Extent(); }
int CadModel::num_vertices() const { return data_->vertices.Extent(); }

std::string CadModel::summary() const {
  return name() + ": " + plural(num_solids(), "solid", "solids") + ", " + plural(num_shells(), "shell", "shells") +
         ", " + plural(num_faces(), "face", "faces") + ", " + plural(num_edges(), "edge", "edges") + ", " +
         plural(num_vertices(), "vertex", "vertices");
}

std::map<std::string, int> CadModel::surface_types() const {
  std::map<std::string, int> m;
  for (const auto& s : data_->surfaces) ++m[s ? s->type : std::string("none")];
  return m;
}

std::map<std::string, int> CadModel::curve_types() const {
  std::map<std::string, int> m;
  for (const auto& c : data_->curves) ++m[c ? c->type : std::string("degenerated")];
  return m;
}

std::array<Eigen::Vector3d, 2> CadModel::bounding_box() const {
  Bnd_Box box;
  if (!data_->shape.IsNull()) BRepBndLib::Add(data_->shape, box);
  if (box.IsVoid()) return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double x0, y0, z0, x1, y1, z1;
  box.Get(x0, y0, z0, x1, y1, z1);
  return {Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1)};
}

double CadModel::size() const {
  const auto b = bounding_box();
  return (b[1] - b[0]).norm();
}

double CadModel::volume() const {
  double v = 0;
  for (int i = 1; i <= data_->solids.Extent(); ++i) {
    GProp_GProps g;
    BRepGProp::VolumeProperties(data_->solids(i), g);
    v += g.Mass();
  }
  return v;
}

double CadModel::area() const {
  double a = 0;
  for (int i = 1; i <= data_->faces.Extent(); ++i) {
    GProp_GProps g;
    BRepGProp::SurfaceProperties(data_->faces(i), g);
    a += g.Mass();
  }
  return a;
}

bool CadModel::valid() const {
  if (data_->shape.IsNull()) return false;
  const BRepCheck_Analyzer check(data_->shape);
  return check.IsValid();
}

const std::vector<std::string>& CadModel::healing() const { return data_->healing; }

OccSurface CadModel::surface(int tag) const {
  check_tag(data_->faces, tag, "face");
  const auto& s = data_->surfaces[tag - 1];
  if (!s) throw std::out_of_range("hom::cad::CadModel: face " + std::to_string(tag) + " has no surface");
  return OccSurface(s);
}

OccCurve CadModel::curve(int tag) const {
  check_tag(data_->edges, tag, "edge");
  const auto& c = data_->curves[tag - 1];
  if (!c) throw std::out_of_range("hom::cad::CadModel: edge " + std::to_string(tag) + " is degenerated (no 3D curve)");
  return OccCurve(c);
}

bool CadModel::degenerated(int tag) const { return !data_->curves[check_tag(data_->edges, tag, "edge") - 1]; }

Eigen::Vector3d CadModel::vertex(int tag) const {
  const gp_Pnt p = BRep_Tool::Pnt(TopoDS::Vertex(data_->vertices(check_tag(data_->vertices, tag, "vertex"))));
  return {p.X(), p.Y(), p.Z()};
}

double CadModel::tolerance(int dim, int tag) const {
  switch (dim) {
    case 0: return BRep_Tool::Tolerance(TopoDS::Vertex(data_->vertices(check_tag(data_->vertices, tag, "vertex"))));
    case 1: return BRep_Tool::Tolerance(TopoDS::Edge(data_->edges(check_tag(data_->edges, tag, "edge"))));
    case 2: return BRep_Tool::Tolerance(TopoDS::Face(data_->faces(check_tag(data_->faces, tag, "face"))));
    default: throw std::out_of_range("hom::cad::CadModel::tolerance: dimension must be 0, 1 or 2");
  }
}

std::vector<int> CadModel::face_edges(int tag) const {
  std::vector<int> out;
  TopTools_IndexedMapOfShape m;
  TopExp::MapShapes(data_->faces(check_tag(data_->faces, tag, "face")), TopAbs_EDGE, m);
  for (int i = 1; i <= m.Extent(); ++i) out.push_back(data_->edges.FindIndex(m(i)));
  return out;
}

std::array<int, 2> CadModel::edge_vertices(int tag) const {
  TopoDS_Vertex a, b;
  // CumOri = false: in the order of the curve's parameter, whatever the
  // edge's orientation where it was first met.
  TopExp::Vertices(TopoDS::Edge(data_->edges(check_tag(data_->edges, tag, "edge"))), a, b, Standard_False);
  return {a.IsNull() ? 0 : data_->vertices.FindIndex(a), b.IsNull() ? 0 : data_->vertices.FindIndex(b)};
}

std::vector<int> CadModel::solid_faces(int tag) const {
  std::vector<int> out;
  TopTools_IndexedMapOfShape m;
  TopExp::MapShapes(data_->solids(check_tag(data_->solids, tag, "solid")), TopAbs_FACE, m);
  for (int i = 1; i <= m.Extent(); ++i) out.push_back(data_->faces.FindIndex(m(i)));
  return out;
}

std::vector<int> CadModel::inner_shell_faces() const {
  std::set<int> out;
  for (int s = 1; s <= data_->solids.Extent(); ++s) {
    const TopoDS_Solid solid = TopoDS::Solid(data_->solids(s));
    const TopoDS_Shell outer = BRepClass3d::OuterShell(solid);
    for (TopExp_Explorer shells(solid, TopAbs_SHELL); shells.More(); shells.Next()) {
      if (shells.Current().IsSame(outer)) continue;
      for (TopExp_Explorer f(shells.Current(), TopAbs_FACE); f.More(); f.Next())
        out.insert(data_->faces.FindIndex(f.Current()));
    }
  }
  return {out.begin(), out.end()};
}

std::vector<int> CadModel::edge_faces(int tag) const {
  const TopoDS_Shape& e = data_->edges(check_tag(data_->edges, tag, "edge"));
  std::vector<int> out;
  for (int f = 1; f <= data_->faces.Extent(); ++f)
    for (TopExp_Explorer ex(data_->faces(f), TopAbs_EDGE); ex.More(); ex.Next())
      if (ex.Current().IsSame(e)) {
        out.push_back(f);
        break;
      }
  return out;
}

Eigen::Vector2d CadModel::edge_uv_on_face(int edge_tag, int face_tag, double t) const {
  TopoDS_Edge e = TopoDS::Edge(data_->edges(check_tag(data_->edges, edge_tag, "edge")));
  const TopoDS_Face& f = TopoDS::Face(data_->faces(check_tag(data_->faces, face_tag, "face")));
  e.Orientation(TopAbs_FORWARD);
  double first = 0, last = 0;
  const Handle(Geom2d_Curve) c = BRep_Tool::CurveOnSurface(e, f, first, last);
  if (c.IsNull())
    throw std::out_of_range("hom::cad::CadModel: edge " + std::to_string(edge_tag) + " has no curve on face " +
                            std::to_string(face_tag));
  const gp_Pnt2d p = c->Value(t);
  const Eigen::Vector2d on_pcurve(p.X(), p.Y());
  double a = 0, b = 0;
  const Handle(Geom_Curve) curve = BRep_Tool::Curve(e, a, b);
  if (curve.IsNull()) return on_pcurve;  // a degenerated edge: its pcurve is all there is
  const gp_Pnt q = curve->Value(t);
  const Eigen::Vector3d x(q.X(), q.Y(), q.Z());
  const OccSurface s = surface(face_tag);
  Eigen::Vector2d uv = ::hom::detail::closest_point_newton(s, x, on_pcurve);
  for (int k = 0; k < 2; ++k) uv[k] = s.range(k).unwrap(uv[k], on_pcurve[k]);
  // Newton only improves on the start; at a pole it may wander in the free
  // parameter without getting closer, so the pcurve's point stays then.
  return (s.evaluate(uv) - x).norm() < (s.evaluate(on_pcurve) - x).norm() - 1e-12 * s.size() ? uv : on_pcurve;
}

GeometryModel<3> CadModel::geometry_model() const {
  GeometryModel<3> g;
  for (int i = 0; i < num_faces(); ++i)
    if (data_->surfaces[i]) g.add_surface(i + 1, OccSurface(data_->surfaces[i]));
  for (int i = 0; i < num_edges(); ++i)
    if (data_->curves[i]) g.add_curve(i + 1, OccCurve(data_->curves[i]));
  return g;
}

std::vector<Entity> CadModel::entities() const {
  const auto& d = *data_;
  std::vector<Entity> out;
  for (int i = 1; i <= d.vertices.Extent(); ++i) out.push_back(Entity{{0, i}, {}, {}});
  for (int i = 1; i <= d.edges.Extent(); ++i) {
    Entity en{{1, i}, {}, {}};
    const auto v = edge_vertices(i);
    for (int t : v)
      if (t > 0 && std::find(en.boundary.begin(), en.boundary.end(), t) == en.boundary.end()) en.boundary.push_back(t);
    out.push_back(std::move(en));
  }
  auto signed_children = [&](const TopoDS_Shape& s, TopAbs_ShapeEnum what, const TopTools_IndexedMapOfShape& map) {
    std::vector<int> b;
    for (TopExp_Explorer ex(s, what); ex.More(); ex.Next()) {
      const int t = map.FindIndex(ex.Current());
      const int st = ex.Current().Orientation() == TopAbs_REVERSED ? -t : t;
      if (t > 0 && std::find(b.begin(), b.end(), st) == b.end()) b.push_back(st);
    }
    return b;
  };
  for (int i = 1; i <= d.faces.Extent(); ++i) out.push_back(Entity{{2, i}, {}, signed_children(d.faces(i), TopAbs_EDGE, d.edges)});
  for (int i = 1; i <= d.solids.Extent(); ++i) out.push_back(Entity{{3, i}, {}, signed_children(d.solids(i), TopAbs_FACE, d.faces)});
  return out;
}

CadModel read_cad(const std::string& path, const CadReadOptions& options) {
  cad_format(path);  // unsupported extension: an error before touching the file
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw CadError(path + ": no such file");
  if (std::filesystem::is_directory(path, ec)) throw CadError(path + ": is a directory, not a CAD file");
  if (!std::ifstream(path)) throw CadError(path + ": cannot open for reading");
  if (std::filesystem::file_size(path, ec) == 0) throw CadError(path + ": empty file");
  const QuietOcc quiet;
  try {
    TopoDS_Shape shape = read_shape(path);
    if (shape.IsNull() || count(shape, TopAbs_FACE) == 0)
      throw CadError(path + ": no faces (the file holds no surface or solid OpenCASCADE could read)");
    std::vector<std::string> log;
    shape = heal(shape, options, log);
    if (count(shape, TopAbs_FACE) == 0) throw CadError(path + ": no faces left after healing");
    return detail::make_model(path, shape, std::move(log));
  } catch (const Standard_Failure& e) {
    throw CadError(path + ": OpenCASCADE failed to read the file (" + failure_text(e) + ")");
  }
}

void write_brep(const CadModel& model, const std::string& path) {
  write_via_temporary(path, [&](const std::string& tmp) { return BRepTools::Write(model.data().shape, tmp.c_str()); });
}

void write_step(const CadModel& model, const std::string& path) {
  write_via_temporary(path, [&](const std::string& tmp) {
    STEPControl_Writer w;
    if (w.Transfer(model.data().shape, STEPControl_AsIs) != IFSelect_RetDone) return false;
    return w.Write(tmp.c_str()) == IFSelect_RetDone;
  });
}

void write_iges(const CadModel& model, const std::string& path) {
  write_via_temporary(path, [&](const std::string& tmp) {
    IGESControl_Controller::Init();
    IGESControl_Writer w("MM", 1);  // mode 1: faces as BRep entities (MSBO), not trimmed surfaces
    if (!w.AddShape(model.data().shape)) return false;
    w.ComputeModel();
    return w.Write(tmp.c_str()) == Standard_True;
  });
}

void write_cad(const CadModel& model, const std::string& path) {
  switch (cad_format(path)) {
    case CadFormat::step: return write_step(model, path);
    case CadFormat::iges: return write_iges(model, path);
    case CadFormat::brep: return write_brep(model, path);
  }
}

// --- built-in models ------------------------------------------------------

namespace {

gp_Pnt pnt(const Eigen::Vector3d& x) { return gp_Pnt(x[0], x[1], x[2]); }

template <class F>
CadModel built(const std::string& name, F&& make) {
  try {
    return detail::make_model(name, make());
  } catch (const Standard_Failure& e) {
    throw std::runtime_error("hom::cad: OpenCASCADE failed to build " + name + " (" + failure_text(e) + ")");
  }
}

}  // namespace

CadModel box_model(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return built("box", [&] { return BRepPrimAPI_MakeBox(pnt(lo), pnt(hi)).Shape(); });
}

CadModel sphere_model(const Eigen::Vector3d& center, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("hom::cad::sphere_model: radius must be positive");
  return built("sphere", [&] { return BRepPrimAPI_MakeSphere(pnt(center), radius).Shape(); });
}

CadModel cylinder_model(const Eigen::Vector3d& base, const Eigen::Vector3d& axis, double radius, double height) {
  if (!(radius > 0) || !(height > 0) || !(axis.norm() > 0))
    throw std::invalid_argument("hom::cad::cylinder_model: need radius > 0, height > 0 and an axis");
  return built("cylinder", [&] {
    return BRepPrimAPI_MakeCylinder(gp_Ax2(pnt(base), gp_Dir(axis[0], axis[1], axis[2])), radius, height).Shape();
  });
}

CadModel cube_with_cavity_model(double side, double sphere_diameter) {
  if (!(side > 0) || !(sphere_diameter > 0) || !(sphere_diameter < side))
    throw std::invalid_argument("hom::cad::cube_with_cavity_model: need 0 < sphere diameter < side");
  return built("cube_with_cavity", [&] {
    const double c = side / 2;
    const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), side, side, side).Shape();
    const TopoDS_Shape ball = BRepPrimAPI_MakeSphere(gp_Pnt(c, c, c), sphere_diameter / 2).Shape();
    BRepAlgoAPI_Cut cut(box, ball);
    if (!cut.IsDone()) throw std::runtime_error("hom::cad::cube_with_cavity_model: OpenCASCADE's cut failed");
    return cut.Shape();
  });
}

CadModel assemble(const std::vector<CadModel>& parts, const std::string& name) {
  if (parts.empty()) throw std::invalid_argument("hom::cad::assemble: no parts");
  return built(name, [&] {
    BRep_Builder builder;
    TopoDS_Compound compound;
    builder.MakeCompound(compound);
    for (const auto& p : parts) builder.Add(compound, p.data().shape);
    return TopoDS_Shape(compound);
  });
}

CadModel nurbs_sphere_model(const Eigen::Vector3d& center, double radius) {
  if (!(radius > 0)) throw std::invalid_argument("hom::cad::nurbs_sphere_model: radius must be positive");
  return built("nurbs_sphere", [&] {
    // Each octant (a quarter of longitude, a hemisphere of latitude) of the
    // sphere converted to an exact rational B-spline (GeomConvert gives the
    // rational quadratic form of the spherical patch), made a face, the 8
    // faces sewn into a closed shell and a solid.
    const Handle(Geom_SphericalSurface) sphere = new Geom_SphericalSurface(gp_Sphere(gp_Ax3(pnt(center), gp::DZ()), radius));
    const double q = std::numbers::pi / 2;
    const double tol = 1e-7 * radius;
    BRepBuilderAPI_Sewing sew(tol);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 2; ++j) {
        const Handle(Geom_RectangularTrimmedSurface) patch =
            new Geom_RectangularTrimmedSurface(sphere, i * q, (i + 1) * q, (j - 1) * q, j * q);
        const Handle(Geom_BSplineSurface) nurbs = GeomConvert::SurfaceToBSplineSurface(patch);
        sew.Add(BRepBuilderAPI_MakeFace(nurbs, tol).Face());
      }
    sew.Perform();
    TopoDS_Shell shell;
    for (TopExp_Explorer ex(sew.SewedShape(), TopAbs_SHELL); ex.More(); ex.Next()) shell = TopoDS::Shell(ex.Current());
    if (shell.IsNull() || !BRep_Tool::IsClosed(shell))
      throw std::runtime_error("hom::cad::nurbs_sphere_model: the 8 patches did not sew into a closed shell");
    ShapeFix_Solid fix;
    return TopoDS_Shape(fix.SolidFromShell(shell));
  });
}

}  // namespace hom::cad
