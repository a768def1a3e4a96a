#pragma once
/// @file cad_model.hpp
/// CAD models read with OpenCASCADE (STEP, IGES, BREP) or built in code,
/// healed, with their topology indexed, for chapter 6's a posteriori
/// pipeline and chapter 5's surfaces. Compiled in src/cad (libhom_cad); this
/// header needs only Eigen and hom's headers.
///
///   auto cad = hom::cad::read_cad("part.step");    // throws CadError
///   std::cout << cad.summary() << "\n";           // "part.step: 1 solid, 128 faces, ..."
///   hom::GeometryModel<3> g = cad.geometry_model(); // face tag -> OccSurface, edge tag -> OccCurve
///
/// Tags: vertices, edges, faces, shells and solids are numbered 1, 2, ...
/// in the order of TopExp::MapShapes (a TopTools_IndexedMapOfShape of the
/// healed shape), so a tag is stable for a given file and OpenCASCADE
/// version. A hom mesh classified on the model (cad_mesher.hpp) uses these
/// tags as entity tags: dimension 0 vertex, 1 edge, 2 face, 3 solid.
///
/// Healing (CadReadOptions; what `read_cad` does after reading):
///   1. if BRepCheck_Analyzer finds the shape invalid, ShapeFix_Shape with
///      the default precision: fixes what the shape analysis finds wrong in
///      solids (orientation of shells), shells
///      (face orientation), faces (missing or wrong pcurves, wire order and
///      orientation, missing seam and degenerated edges at poles, small and
///      self-intersecting wires) and edges (same-parameter, vertex
///      tolerances). A valid shape is left alone: ShapeFix still retouches
///      valid shapes, and Gmsh 4.8.4 then fails on some it meshes as read;
///   2. if the shape has free edges (edges bounding one face only) and more
///      than one face, BRepBuilderAPI_Sewing joins faces along coincident
///      edges (IGES files and STEP files of loose faces or open shells come
///      unsewn; a surface mesh of unsewn faces would not be conforming);
///      the tolerance is 1e-6 times the bounding-box diagonal;
///   3. if the shape has closed shells but no solid, each closed shell
///      becomes a solid (ShapeFix_Solid), so that it can be meshed in 3D;
///   4. on request (merge_small_edges > 0), edges shorter than that are
///      dropped and their neighbours on the wire joined at one vertex
///      (ShapeFix_Wireframe::FixSmallEdges in drop mode). Every model vertex
///      is a mesh node, so a CAD edge far shorter than the elements (0.036
///      beside elements of 7 to 14 in wing_fuselage.step) forces a tiny mesh
///      edge and slivers around it. Dropping an edge moves the faces near it
///      by about its length and renumbers the model's edges and vertices.
/// `healing()` lists the steps that changed something.

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hom/geometry/geometry_model.hpp"
#include "hom/io/error.hpp"
#include "hom/mesh/mesh.hpp"
#include "occ_curve.hpp"
#include "occ_surface.hpp"

namespace hom::cad {

/// A CAD file that cannot be used: missing, unreadable, empty, of an
/// unsupported kind; the message names the file.
class CadError : public io::IoError {
 public:
  using io::IoError::IoError;
};

enum class CadFormat { step, iges, brep };

/// The format of a file name by its extension (.step/.stp, .iges/.igs,
/// .brep/.brp, any case); throws CadError naming the file otherwise.
CadFormat cad_format(const std::string& path);

struct CadReadOptions {
  bool heal = true;         ///< ShapeFix_Shape if the shape is invalid (step 1 above)
  bool sew = true;          ///< sew faces with free edges (step 2)
  bool make_solids = true;  ///< closed shells without solids become solids (step 3)
  double merge_small_edges = 0.0;  ///< step 4: edges shorter than this dropped; 0: off
};

namespace detail {
struct CadModelData;
}  // namespace detail

class CadModel {
 public:
  /// An empty model (no shape).
  CadModel();
  explicit CadModel(std::shared_ptr<const detail::CadModelData> data);

  /// The file name, or the built-in model's name.
  const std::string& name() const;

  int num_solids() const;
  int num_shells() const;
  int num_faces() const;
  int num_edges() const;
  int num_vertices() const;

  /// "NAME: 1 solid, 1 shell, 7 faces, 15 edges, 10 vertices" (one line).
  std::string summary() const;
  /// Faces per surface kind ("plane", "sphere", "bspline", ...).
  std::map<std::string, int> surface_types() const;
  /// Edges per curve kind ("line", "circle", ...; "degenerated" for edges
  /// without a 3D curve, collapsed at a pole).
  std::map<std::string, int> curve_types() const;
  /// Axis-aligned bounding box (lo, hi) of the shape.
  std::array<Eigen::Vector3d, 2> bounding_box() const;
  /// Diagonal of the bounding box.
  double size() const;
  /// Total volume of the solids and total area of the faces (BRepGProp).
  double volume() const;
  double area() const;
  /// Whether BRepCheck_Analyzer finds the shape valid.
  bool valid() const;
  /// What healing changed (empty if nothing).
  const std::vector<std::string>& healing() const;

  /// The geometry of face `tag` / edge `tag` (1-based). curve() throws
  /// std::out_of_range for a degenerated edge (it has no 3D curve).
  OccSurface surface(int face_tag) const;
  OccCurve curve(int edge_tag) const;
  bool degenerated(int edge_tag) const;
  Eigen::Vector3d vertex(int vertex_tag) const;
  /// OpenCASCADE's tolerance of a vertex, edge or face (the gap the model
  /// admits there); dim 0, 1 or 2.
  double tolerance(int dim, int tag) const;

  /// Topology (tags): the edges of a face, the vertices of an edge (at the
  /// start and end of its parameter range; equal for a closed edge), the faces of a solid, the faces that an
  /// edge bounds.
  std::vector<int> face_edges(int face_tag) const;
  std::array<int, 2> edge_vertices(int edge_tag) const;
  std::vector<int> solid_faces(int solid_tag) const;
  /// Faces of the solids' inner shells (the walls of cavities: a body inside
  /// a far-field domain), sorted; empty when no solid has a cavity.
  std::vector<int> inner_shell_faces() const;
  std::vector<int> edge_faces(int edge_tag) const;
  /// The (u, v) on face `face_tag` of the point of edge `edge_tag` at its
  /// parameter t: the closest point of the surface to the edge's 3D point
  /// C(t), found by Newton's method from the edge's pcurve on the face (for a
  /// seam edge the pcurve of the edge's forward orientation), periodic
  /// parameters next to the pcurve's. A file's pcurve may stray from its 3D
  /// curve (t106_turbine_cascade.step: by 0.67 in space and 1.8 at equal
  /// parameters); then S(pcurve(t)) is not the node at C(t), and a face
  /// element would be checked with its boundary nodes elsewhere.
  Eigen::Vector2d edge_uv_on_face(int edge_tag, int face_tag, double t) const;

  /// Face tags -> OccSurface and edge tags -> OccCurve (degenerated edges
  /// have none), as hom's run-time geometry of a classified mesh.
  GeometryModel<3> geometry_model() const;
  /// The model's entities as a hom mesh lists them: vertices, edges (bounded
  /// by their vertices), faces (by their edges, negative if reversed in the
  /// face) and solids (by their faces, negative if reversed).
  std::vector<Entity> entities() const;

  /// The OpenCASCADE side (src/cad internals only).
  const detail::CadModelData& data() const { return *data_; }

 private:
  std::shared_ptr<const detail::CadModelData> data_;
};

/// Reads a STEP, IGES or BREP file (format from the extension), heals it,
/// indexes it. Throws CadError naming the file if it is missing, unreadable,
/// has no faces, or has an unsupported extension. STEP and IGES lengths are
/// in millimetres (OpenCASCADE's default unit conversion).
CadModel read_cad(const std::string& path, const CadReadOptions& options = {});

/// Writes the model's shape; the file appears only complete (written to
/// PATH.tmp.EXT and renamed). Throws CadError on failure.
void write_brep(const CadModel& model, const std::string& path);
void write_step(const CadModel& model, const std::string& path);
void write_iges(const CadModel& model, const std::string& path);
/// Writes in the format of the extension.
void write_cad(const CadModel& model, const std::string& path);

// --- models built with OpenCASCADE in code --------------------------------

/// The box [lo, hi].
CadModel box_model(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
/// A full sphere (one spherical face, u longitude in [0, 2 pi) from the x
/// axis, v latitude; BRepPrimAPI_MakeSphere).
CadModel sphere_model(const Eigen::Vector3d& center, double radius);
/// A full cylinder of the given radius and height on the axis through
/// `base` with direction `axis` (lateral face u angle, v height; two disks).
CadModel cylinder_model(const Eigen::Vector3d& base, const Eigen::Vector3d& axis, double radius, double height);
/// The cube [0, side]^3 minus a ball of diameter `sphere_diameter` at its
/// centre (thesis section 4.3.1; the same model src/meshing/cube_with_cavity
/// builds with Gmsh's OpenCASCADE kernel).
CadModel cube_with_cavity_model(double side = 5.0, double sphere_diameter = 1.0);
/// A sphere made of 8 octant faces, each an exact rational quadratic
/// B-spline (NURBS) patch, sewn into one closed shell and one solid
/// (section 6.3.3.1's sphere described by a NURBS CAD).
CadModel nurbs_sphere_model(const Eigen::Vector3d& center = Eigen::Vector3d::Zero(), double radius = 0.5);
/// The parts' solids (and faces) in one model, a compound in which parts
/// share no topology: where two parts touch, each keeps its own faces, as a
/// body and the far field around it often come from CAD. Tags follow the
/// order of the parts (the first part's solids first). A model given twice
/// is the same shape and counts once.
CadModel assemble(const std::vector<CadModel>& parts, const std::string& name = "assembly");

}  // namespace hom::cad
