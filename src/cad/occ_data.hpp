#pragma once
/// @file occ_data.hpp
/// The OpenCASCADE objects behind CadModel, OccSurface and OccCurve.
/// Internal to src/cad (includes OpenCASCADE headers); hom_cad's public
/// headers only forward-declare these.

#include <memory>
#include <string>
#include <vector>

#include <BRepTopAdaptor_FClass2d.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>

#include <Eigen/Core>

#include "cad_model.hpp"

namespace hom::cad::detail {

struct OccSurfaceData {
  TopoDS_Face face;
  Handle(Geom_Surface) surface;       // with the face's location applied
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;  // UV box of the face
  bool periodic[2] = {false, false};
  double period[2] = {0, 0};
  // Periodic for hom, but only closed for OpenCASCADE (S(U1, v) = S(U2, v)
  // along a seam): evaluated at the representative in [lo, lo + period).
  bool closed_only[2] = {false, false};
  double size = 0;                    // bounding-box diagonal
  std::string type;
  int grid_u = 0, grid_v = 0;         // projection start grid
  std::vector<Eigen::Vector3d> grid;  // S at the grid's points, u fastest
  std::unique_ptr<BRepTopAdaptor_FClass2d> classifier;  // inside / outside the trimmed face
};

struct OccCurveData {
  TopoDS_Edge edge;
  Handle(Geom_Curve) curve;  // with the edge's location applied
  double first = 0, last = 0;
  bool periodic = false;
  double length = 0;
  std::string type;
  std::vector<Eigen::Vector3d> samples;  // C at 64 + 1 equispaced parameters
};

struct CadModelData {
  std::string name;
  TopoDS_Shape shape;
  TopTools_IndexedMapOfShape solids, shells, faces, edges, vertices;
  std::vector<std::string> healing;
  // Geometry, built once (shared by every copy of the model).
  std::vector<std::shared_ptr<const OccSurfaceData>> surfaces;  // index tag - 1
  std::vector<std::shared_ptr<const OccCurveData>> curves;      // null for degenerated edges
};

/// A model of `shape`: indexes its sub-shapes and builds their geometry.
CadModel make_model(std::string name, const TopoDS_Shape& shape, std::vector<std::string> healing = {});

std::shared_ptr<const OccSurfaceData> make_surface_data(const TopoDS_Face& face);
std::shared_ptr<const OccCurveData> make_curve_data(const TopoDS_Edge& edge);  // null if degenerated

}  // namespace hom::cad::detail
