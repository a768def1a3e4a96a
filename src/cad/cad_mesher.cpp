// Meshing a CadModel with Gmsh and classifying mesh nodes on the model
// (cad_mesher.hpp).

#include "cad_mesher.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <numbers>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/point.hpp>
#include <boost/geometry/strategies/strategies.hpp>
#include <boost/geometry/index/rtree.hpp>

#include <BRepBndLib.hxx>
#include <Bnd_Box.hxx>
#include <TopoDS.hxx>

#include "ears.hpp"
#include "gmsh_model.hpp"
#include "meshing_error.hpp"
#include "occ_data.hpp"

namespace hom::cad {

namespace {

using Box = std::array<Eigen::Vector3d, 2>;

Box shape_box(const TopoDS_Shape& s, double pad) {
  Bnd_Box b;
  BRepBndLib::Add(s, b);
  if (b.IsVoid()) return {Eigen::Vector3d::Constant(-1e300), Eigen::Vector3d::Constant(1e300)};
  double x0, y0, z0, x1, y1, z1;
  b.Get(x0, y0, z0, x1, y1, z1);
  return {Eigen::Vector3d(x0 - pad, y0 - pad, z0 - pad), Eigen::Vector3d(x1 + pad, y1 + pad, z1 + pad)};
}

bool in_box(const Box& b, const Eigen::Vector3d& x) {
  return (x.array() >= b[0].array()).all() && (x.array() <= b[1].array()).all();
}

std::string point_text(const Eigen::Vector3d& x) {
  std::ostringstream o;
  o.precision(9);
  o << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return o.str();
}

const char* dim_word(int dim) {
  static const char* w[] = {"point", "curve", "surface", "volume"};
  return w[std::clamp(dim, 0, 3)];
}

// Points of a Gmsh curve / surface: a spread of its mesh nodes, or (no nodes
// of its own) a curve's middle; none for a surface without nodes. Positions
// only: Gmsh 4.8.4 leaves wrong parametric coordinates on the nodes its quad
// subdivision adds.
std::vector<Eigen::Vector3d> probes(const io::MshData& d, const std::vector<std::size_t>& nodes, int dim, int tag) {
  std::vector<Eigen::Vector3d> out;
  const std::size_t step = std::max<std::size_t>(1, nodes.size() / 7);
  for (std::size_t k = 0; k < nodes.size(); k += step) {
    const auto& n = d.nodes[nodes[k]];
    out.emplace_back(n.x[0], n.x[1], n.x[2]);
  }
  if (!out.empty()) return out;
  if (dim == 1) {
    std::vector<double> lo, hi, x;
    gmsh::model::getParametrizationBounds(1, tag, lo, hi);
    gmsh::model::getValue(1, tag, {(lo.at(0) + hi.at(0)) / 2}, x);
    out.emplace_back(x.at(0), x.at(1), x.at(2));
    return out;
  }
  return out;  // a surface without nodes of its own: its boundary decides
}

// Gmsh tag -> model tag for the Gmsh entities of dimension 1 or 2. The
// candidates are the model entities with the same boundary (a curve's end
// vertices, a surface's non-degenerated edges, already matched); among
// several (two arcs between the same vertices, coincident entities of two
// solids that do not share them) the nearest to the Gmsh entity's probes
// (fewest probes outside a face's trimming first), then the one with Gmsh's
// tag (Gmsh numbers an imported shape's entities in the order hom indexes
// them), then one not taken yet. Probes farther than `loose` from every
// candidate make an error; Gmsh entities without a boundary that matches
// and without mesh nodes (degenerated edges) are left out.
std::map<int, int> match_entities(const CadModel& cad, const io::MshData& d, int dim, double loose,
                                  const std::map<int, std::vector<std::size_t>>& nodes_by_entity,
                                  const std::map<int, int>& lower_map) {
  std::map<int, int> out;
  std::map<int, int> used;  // model tag -> Gmsh tag
  gmsh::vectorpair entities;
  gmsh::model::getEntities(entities, dim);
  const int count = dim == 1 ? cad.num_edges() : cad.num_faces();
  std::vector<std::set<int>> model_boundary(count + 1);
  for (int t = 1; t <= count; ++t) {
    if (dim == 1) {
      const auto v = cad.edge_vertices(t);
      model_boundary[t] = {v[0], v[1]};
    } else {
      for (int e : cad.face_edges(t))
        if (!cad.degenerated(e)) model_boundary[t].insert(e);
    }
  }
  for (const auto& [dd, tag] : entities) {
    std::set<int> boundary;
    gmsh::vectorpair bnd;
    gmsh::model::getBoundary({{dim, tag}}, bnd, false, false, false);
    for (const auto& b : bnd)
      if (auto m = lower_map.find(std::abs(b.second)); m != lower_map.end()) boundary.insert(m->second);
    const auto it = nodes_by_entity.find(tag);
    const std::vector<std::size_t> none;
    const auto pr = probes(d, it == nodes_by_entity.end() ? none : it->second, dim, tag);
    struct Candidate {
      int tag;
      int outside;
      double distance;
    };
    std::vector<Candidate> fits;
    for (int t = 1; t <= count; ++t) {
      if ((dim == 1 && cad.degenerated(t)) || model_boundary[t] != boundary) continue;
      Candidate c{t, 0, 0.0};
      for (const auto& x : pr) {
        if (dim == 1) {
          const auto curve = cad.curve(t);
          c.distance = std::max(c.distance, (curve.evaluate(curve.project(x)) - x).norm());
        } else {
          const auto s = cad.surface(t);
          const Eigen::Vector2d uv = s.project(x);
          c.distance = std::max(c.distance, (s.evaluate(uv) - x).norm());
          c.outside += !s.contains(uv);
        }
      }
      if (c.distance <= loose) fits.push_back(c);
    }
    if (fits.empty()) {
      if (it == nodes_by_entity.end()) continue;  // no mesh on it: nothing to classify
      throw MeshingError(cad.name() + ": Gmsh " + dim_word(dim) + " " + std::to_string(tag) + " matches no model " +
                         (dim == 1 ? "edge" : "face") + " (none has its boundary and passes within " +
                         std::to_string(loose) + " of its mesh node " + point_text(pr.front()) + ")");
    }
    auto rank = [&](const Candidate& c) {
      return std::make_tuple(c.outside, c.distance > 1e-3 * loose, c.tag != tag, used.count(c.tag) > 0, c.distance);
    };
    std::stable_sort(fits.begin(), fits.end(), [&](const Candidate& a, const Candidate& b) { return rank(a) < rank(b); });
    if (const auto [u, fresh] = used.emplace(fits.front().tag, tag); !fresh)
      throw MeshingError(cad.name() + ": Gmsh " + dim_word(dim) + "s " + std::to_string(u->second) + " and " +
                         std::to_string(tag) + " both match model " + (dim == 1 ? "edge " : "face ") +
                         std::to_string(fits.front().tag));
    out[tag] = fits.front().tag;
  }
  return out;
}

// The entities of the chosen solids' closure: the solids, their faces, the
// faces' edges and the edges' end vertices.
std::set<EntityId> solid_closure(const CadModel& cad, const std::vector<int>& solids) {
  std::set<EntityId> kept;
  for (int s : solids) {
    kept.insert({3, s});
    for (int f : cad.solid_faces(s)) {
      kept.insert({2, f});
      for (int e : cad.face_edges(f)) {
        kept.insert({1, e});
        for (int v : cad.edge_vertices(e)) kept.insert({0, v});
      }
    }
  }
  return kept;
}

// Keeps the elements on the entities of `kept` (model tags), the nodes they
// use and those entities; element node lists are rebuilt.
void keep_entities(io::MshData& d, const std::set<EntityId>& kept) {
  std::vector<io::MshElement> elements;
  std::vector<std::int64_t> element_nodes;
  std::set<std::int64_t> used;
  for (const auto& e : d.elements) {
    if (!kept.count(e.entity)) continue;
    const auto nodes = d.nodes_of(e);
    io::MshElement k = e;
    k.first = element_nodes.size();
    element_nodes.insert(element_nodes.end(), nodes.begin(), nodes.end());
    used.insert(nodes.begin(), nodes.end());
    elements.push_back(k);
  }
  std::erase_if(d.nodes, [&](const io::MshNode& n) { return !used.count(n.tag); });
  std::erase_if(d.entities, [&](const Entity& en) { return !kept.count(en.id); });
  d.elements = std::move(elements);
  d.element_nodes = std::move(element_nodes);
}

// A long sliver: a linear triangle or quadrilateral (corners in cyclic
// order) wider than `width` with a corner angle below `angle` (radians).
bool long_sliver(const std::vector<Eigen::Vector3d>& corners, double width, double angle) {
  const std::size_t n = corners.size();
  double widest = 0, sharpest = std::numbers::pi;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d a = corners[(k + 1) % n] - corners[k], b = corners[(k + n - 1) % n] - corners[k];
    sharpest = std::min(sharpest, std::atan2(a.cross(b).norm(), a.dot(b)));
    for (std::size_t j = k + 1; j < n; ++j) widest = std::max(widest, (corners[j] - corners[k]).norm());
  }
  return widest > width && sharpest < angle;
}

// The Gmsh surfaces whose mesh has a long sliver (above).
std::vector<int> faces_with_long_slivers(double width, double angle) {
  std::vector<std::size_t> tags;
  std::vector<double> xyz, uv;
  gmsh::model::mesh::getNodes(tags, xyz, uv, -1, -1, false, false);
  std::map<std::size_t, Eigen::Vector3d> x;
  for (std::size_t i = 0; i < tags.size(); ++i) x[tags[i]] = Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  std::vector<int> out;
  gmsh::vectorpair faces;
  gmsh::model::getEntities(faces, 2);
  for (const auto& [dim, face] : faces) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> elements, nodes;
    gmsh::model::mesh::getElements(types, elements, nodes, 2, face);
    bool found = false;
    for (std::size_t t = 0; t < types.size() && !found; ++t) {
      const std::size_t n = elements[t].empty() ? 0 : nodes[t].size() / elements[t].size();
      std::vector<Eigen::Vector3d> corners(n);
      for (std::size_t first = 0; first + n <= nodes[t].size() && !found; first += n) {
        for (std::size_t k = 0; k < n; ++k) corners[k] = x.at(nodes[t][first + k]);
        found = long_sliver(corners, width, angle);
      }
    }
    if (found) out.push_back(face);
  }
  return out;
}

// Gmsh's Frontal-Delaunay can lay slivers across a whole face of a B-spline
// patch collapsed at one corner (wing_fuselage.step's wing-root fairing:
// triangles 127 long at size 46, angles of 0.1 degrees), which no curving
// makes valid. The faces with slivers wider than `width` and sharper than 3
// degrees are meshed again with MeshAdapt (Gmsh's algorithm 1), which meshes
// those at the size; the others come out as before (Mesh.RandomSeed fixes
// them). Merely stretched elements (t106_turbine_cascade.step: 94 long at
// size 46, angles of 10 degrees) do not count: MeshAdapt would mesh their
// face three times finer. Returns the Gmsh tags of the faces meshed again.
std::vector<int> remesh_sliver_faces(double width) {
  const auto faces = faces_with_long_slivers(width, 3 * std::numbers::pi / 180);
  if (faces.empty()) return {};
  for (int face : faces) gmsh::model::mesh::setAlgorithm(2, face, 1);
  gmsh::model::mesh::clear();
  gmsh::model::mesh::generate(2);
  return faces;
}

// The local sizes as Gmsh's background field: one Ball each, their minimum
// (Gmsh then takes the smaller of it and the other sizes).
void add_local_sizes(const std::vector<LocalSize>& balls, double scale, double max_size) {
  namespace field = gmsh::model::mesh::field;
  std::vector<double> tags;
  for (const auto& b : balls) {
    const int f = field::add("Ball");
    field::setNumber(f, "Radius", b.radius);
    field::setNumber(f, "Thickness", b.radius);
    field::setNumber(f, "VIn", scale * b.size);
    field::setNumber(f, "VOut", max_size);
    field::setNumber(f, "XCenter", b.center.x());
    field::setNumber(f, "YCenter", b.center.y());
    field::setNumber(f, "ZCenter", b.center.z());
    tags.push_back(f);
  }
  const int smallest = field::add("Min");
  field::setNumbers(smallest, "FieldsList", tags);
  field::setAsBackgroundMesh(smallest);
}

// An earlier mesh's size at a point (CadMeshOptions::earlier_sizes): the
// mean of the sizes at its vertices within r = 2 d + h of the point, weighted
// by (1 - distance / r)^2, d the distance to the nearest vertex and h the
// smallest size. The size is continuous: a vertex enters or leaves the mean
// with weight 0. (The nearest vertex's size alone jumps between vertices;
// with it Gmsh's 1D meshing of t106_turbine_cascade.step's curves filled
// 3 GB at the default integration precision, see EarlierSizes.)
class EarlierSize {
 public:
  explicit EarlierSize(const SizeMap& map)
      : sizes_(map.sizes), smallest_(*std::min_element(map.sizes.begin(), map.sizes.end())) {
    std::vector<Entry> entries;
    for (std::size_t i = 0; i < map.points.size(); ++i) entries.emplace_back(point(map.points[i]), i);
    tree_ = Tree(entries.begin(), entries.end());  // bulk loading
  }
  double operator()(const Eigen::Vector3d& x) const {
    namespace bgi = boost::geometry::index;
    std::vector<Entry> near;
    tree_.query(bgi::nearest(point(x), 1), std::back_inserter(near));
    const double r = 2 * (point_of(near.front()) - x).norm() + smallest_;
    near.clear();
    const Eigen::Vector3d reach = Eigen::Vector3d::Constant(r);
    tree_.query(bgi::intersects(Box(point(x - reach), point(x + reach))), std::back_inserter(near));
    double weights = 0, sum = 0;
    for (const auto& entry : near) {
      const double d = (point_of(entry) - x).norm();
      if (d >= r) continue;
      const double w = (1 - d / r) * (1 - d / r);
      weights += w;
      sum += w * sizes_[entry.second];
    }
    return sum / weights;  // the nearest vertex has d < r
  }

 private:
  using Point = boost::geometry::model::point<double, 3, boost::geometry::cs::cartesian>;
  using Box = boost::geometry::model::box<Point>;
  using Entry = std::pair<Point, std::size_t>;
  using Tree = boost::geometry::index::rtree<Entry, boost::geometry::index::quadratic<16>>;
  static Point point(const Eigen::Vector3d& x) { return Point(x.x(), x.y(), x.z()); }
  static Eigen::Vector3d point_of(const Entry& e) {
    return Eigen::Vector3d(e.first.get<0>(), e.first.get<1>(), e.first.get<2>());
  }
  std::vector<double> sizes_;
  double smallest_;
  Tree tree_;
};

// Gmsh's size callback with the earlier mesh's sizes for as long as it lives
// (Gmsh keeps one callback per process, beyond this model).
class EarlierSizes {
 public:
  EarlierSizes(const SizeMap& map, double floor, double scale) {
    if (map.empty()) return;
    auto size = std::make_shared<const EarlierSize>(map);
    gmsh::model::mesh::setSizeCallback([size, floor, scale](int, int, double x, double y, double z) {
      return scale * std::max(floor, (*size)(Eigen::Vector3d(x, y, z)));
    });
    // Gmsh integrates 1 / size along each curve to place its nodes, halving
    // the steps until two estimates agree to this absolute precision (default
    // 1e-9), which a size blended between vertices hardly meets: on
    // t106_turbine_cascade.step's curves 733 686 calls and 37 s at 1e-9,
    // 20 990 calls and 0.9 s at 1e-4 (gmsh 4.8 from Python, 2026-12-06).
    gmsh::option::getNumber("Mesh.LcIntegrationPrecision", precision_);
    gmsh::option::setNumber("Mesh.LcIntegrationPrecision", 1e-4);
    set_ = true;
  }
  ~EarlierSizes() {
    if (!set_) return;
    try {
      gmsh::model::mesh::removeSizeCallback();
      gmsh::option::setNumber("Mesh.LcIntegrationPrecision", precision_);
    } catch (...) {  // a destructor must not throw
    }
  }
  EarlierSizes(const EarlierSizes&) = delete;
  EarlierSizes& operator=(const EarlierSizes&) = delete;

 private:
  bool set_ = false;
  double precision_ = 0.0;  ///< Mesh.LcIntegrationPrecision before, put back on exit
};

}  // namespace

double size_floor(const CadMeshOptions& o) {
  double floor = o.size_min;
  if (floor > 0)
    for (const auto& b : o.local_sizes) floor = std::min(floor, b.size);
  return floor;
}

double default_mesh_size(const CadModel& cad) { return cad.size() / 20; }

void check_size_fields(const CadModel& cad, const CadMeshOptions& o) {
  for (std::size_t i = 0; i < o.local_sizes.size(); ++i) {
    const auto& b = o.local_sizes[i];
    if (!(b.radius > 0 && b.size > 0 && std::isfinite(b.radius) && std::isfinite(b.size)) || !b.center.allFinite())
      throw std::invalid_argument("local size " + std::to_string(i + 1) +
                                  ": needs a finite center, a finite radius > 0 and a finite size > 0");
  }
  for (const auto& [v, h] : o.vertex_sizes) {
    if (v < 1 || v > cad.num_vertices())
      throw std::invalid_argument("vertex size at vertex " + std::to_string(v) + ": " + cad.name() +
                                  " has vertices 1.." + std::to_string(cad.num_vertices()));
    if (!(h > 0 && std::isfinite(h)))
      throw std::invalid_argument("vertex size at vertex " + std::to_string(v) + ": needs a finite size > 0");
  }
  const auto& earlier = o.earlier_sizes;
  if (earlier.points.size() != earlier.sizes.size())
    throw std::invalid_argument("earlier sizes: " + std::to_string(earlier.points.size()) + " points but " +
                                std::to_string(earlier.sizes.size()) + " sizes");
  for (std::size_t i = 0; i < earlier.points.size(); ++i)
    if (!earlier.points[i].allFinite() || !(earlier.sizes[i] > 0 && std::isfinite(earlier.sizes[i])))
      throw std::invalid_argument("earlier size " + std::to_string(i + 1) +
                                  ": needs a finite point and a finite size > 0");
}

io::MshData cad_mesh_data(const CadModel& cad, const CadMeshOptions& o) {
  if (o.dim != 2 && o.dim != 3) throw std::invalid_argument("hom::cad::cad_mesh_data: dim must be 2 or 3");
  if (cad.num_faces() == 0) throw MeshingError(cad.name() + ": the model has no faces to mesh");
  if (o.dim == 3 && cad.num_solids() == 0)
    throw MeshingError(cad.name() + ": the model has no solid (only surfaces): it can be meshed in 2D (surface mesh) only");
  for (int s : o.solids)
    if (s < 1 || s > cad.num_solids())
      throw MeshingError(cad.name() + ": no solid " + std::to_string(s) + " (the model has " +
                         (cad.num_solids() == 0 ? std::string("no solids") : "solids 1.." + std::to_string(cad.num_solids())) +
                         ")");
  check_size_fields(cad, o);
  const double size = cad.size();
  const double tol = o.tolerance * size;
  // Gmsh 4.8.4's quad subdivision puts the nodes it adds near, not on, the
  // surfaces (with wrong parametric coordinates): those are projected onto
  // their entity if they are within `loose` of it.
  const double loose = o.quads ? 1e-3 * size : tol;
  const double scale = o.quads ? 2.0 : 1.0;  // sizes before the quad subdivision (below)
  const meshing::GmshSession session({o.verbose, o.threads, cad.name(), o.time_limit_s});
  const EarlierSizes earlier(o.earlier_sizes, o.size_min, scale);
  io::MshData d;
  std::map<int, int> maps[4];  // Gmsh tag -> model tag, per dimension
  const double max_size = scale * (o.size > 0 ? o.size : default_mesh_size(cad));
  std::vector<int> remeshed;  // Gmsh surfaces meshed again with MeshAdapt
  try {
    meshing::gmsh_call([&] {
      gmsh::model::add("hom_cad");
      gmsh::option::setNumber("General.NumThreads", o.threads);
      gmsh::option::setNumber("Mesh.RandomSeed", o.seed);
      gmsh::option::setNumber("Mesh.Algorithm", o.algorithm_2d > 0 ? o.algorithm_2d : 6);
      gmsh::option::setNumber("Mesh.Algorithm3D", o.algorithm_3d);
      gmsh::option::setNumber("Mesh.ElementOrder", 1);
      gmsh::option::setNumber("Mesh.MeshSizeMax", max_size);
      if (o.size_min > 0) gmsh::option::setNumber("Mesh.MeshSizeMin", scale * size_floor(o));
      // The earlier mesh's sizes hold its curvature sizing (SizeMap).
      gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", o.earlier_sizes.empty() ? o.size_from_curvature : 0);
      if (o.quads) {
        // Quadrilaterals only (hom reads one element family per mesh):
        // Blossom recombination, then every element split into quads
        // (Mesh.SubdivisionAlgorithm 1), which halves the size, so the
        // triangles are made twice as large. (Gmsh 4.8.4's full-quad
        // recombination, RecombinationAlgorithm 3, can throw from inside an
        // OpenMP region on real models, which aborts the process.)
        gmsh::option::setNumber("Mesh.RecombineAll", 1);
        gmsh::option::setNumber("Mesh.RecombinationAlgorithm", 1);
        gmsh::option::setNumber("Mesh.SubdivisionAlgorithm", 1);
      }
      gmsh::vectorpair imported;
      gmsh::model::occ::importShapesNativePointer(&cad.data().shape, imported, false);
      gmsh::model::occ::synchronize();
      if (!o.local_sizes.empty()) add_local_sizes(o.local_sizes, scale, max_size);

      // Points: by position.
      gmsh::vectorpair points;
      gmsh::model::getEntities(points, 0);
      std::set<int> taken;
      for (const auto& [dd, tag] : points) {
        std::vector<double> x;
        gmsh::model::getValue(0, tag, {}, x);
        const Eigen::Vector3d p(x.at(0), x.at(1), x.at(2));
        // The nearest model vertex; among coincident ones (two solids that
        // share a face but not its vertices) the one with Gmsh's tag, then
        // one not taken yet.
        int best = 0;
        auto rank = [&](int v) {
          const double dv = (cad.vertex(v) - p).norm();
          return std::make_tuple(dv > std::max(tol, cad.tolerance(0, v)), v != tag, taken.count(v) > 0, dv);
        };
        for (int v = 1; v <= cad.num_vertices(); ++v)
          if (best == 0 || rank(v) < rank(best)) best = v;
        if (best == 0 || std::get<0>(rank(best)))
          throw MeshingError(cad.name() + ": Gmsh point " + std::to_string(tag) + " at " + point_text(p) +
                             " is no vertex of the model");
        taken.insert(best);
        maps[0][tag] = best;
        if (auto s = o.vertex_sizes.find(best); s != o.vertex_sizes.end()) gmsh::model::mesh::setSize({{0, tag}}, scale * s->second);
      }
      gmsh::model::mesh::generate(2);
      if (o.algorithm_2d <= 0) remeshed = remesh_sliver_faces(2 * max_size);
      if (o.dim == 3) gmsh::model::mesh::generate(3);
    });
    d = meshing::gmsh_model_data(cad.name());
    meshing::gmsh_call([&] {
      std::map<int, std::vector<std::size_t>> nodes_by_entity[3];
      for (std::size_t i = 0; i < d.nodes.size(); ++i)
        if (d.nodes[i].entity && d.nodes[i].entity->dim >= 1 && d.nodes[i].entity->dim <= 2)
          nodes_by_entity[d.nodes[i].entity->dim][d.nodes[i].entity->tag].push_back(i);
      for (int dim : {1, 2}) maps[dim] = match_entities(cad, d, dim, loose, nodes_by_entity[dim], maps[dim - 1]);
      // Volumes: the solid with the same faces.
      gmsh::vectorpair volumes;
      gmsh::model::getEntities(volumes, 3);
      for (const auto& [dd, tag] : volumes) {
        gmsh::vectorpair bnd;
        gmsh::model::getBoundary({{3, tag}}, bnd, false, false, false);
        std::set<int> faces;
        for (const auto& b : bnd)
          if (auto f = maps[2].find(std::abs(b.second)); f != maps[2].end()) faces.insert(f->second);
        for (int s = 1; s <= cad.num_solids(); ++s) {
          const auto sf = cad.solid_faces(s);
          if (std::set<int>(sf.begin(), sf.end()) == faces) maps[3][tag] = s;
        }
        if (!maps[3].count(tag)) {
          std::ostringstream list;  // (not string +=: GCC 12 -O3 warns falsely, -Wrestrict)
          for (int f : faces) list << ' ' << f;
          throw MeshingError(cad.name() + ": Gmsh volume " + std::to_string(tag) +
                             " matches no solid of the model (its faces are model faces" + list.str() + ")");
        }
      }
    });
    meshing::gmsh_call([] { gmsh::model::remove(); });
  } catch (const MeshingError&) {
    try {
      gmsh::model::remove();
    } catch (...) {
    }
    throw;
  } catch (const std::exception& e) {
    try {
      gmsh::model::remove();
    } catch (...) {
    }
    throw MeshingError(cad.name() + ": meshing failed: " + e.what());
  }

  if (!remeshed.empty() && o.progress) {
    std::ostringstream line;
    line.precision(3);
    line << "linear mesh: CAD face" << (remeshed.size() > 1 ? "s" : "");
    for (int f : remeshed) line << ' ' << (maps[2].count(f) ? maps[2].at(f) : f);
    line << " meshed again with MeshAdapt (Frontal-Delaunay left slivers there wider than " << 2 * max_size << ")";
    o.progress(line.str());
  }

  // Relabel with the model's tags.
  auto remap = [&](EntityId& id) {
    if (id.dim < 0 || id.dim > 3) return false;
    const auto it = maps[id.dim].find(id.tag);
    if (it == maps[id.dim].end()) return false;
    id.tag = it->second;
    return true;
  };
  std::vector<Entity> entities;
  for (auto en : d.entities) {
    if (!remap(en.id)) continue;
    std::vector<int> b;
    for (int t : en.boundary) {
      EntityId c{en.id.dim - 1, std::abs(t)};
      if (en.id.dim > 0 && remap(c)) b.push_back(t < 0 ? -c.tag : c.tag);
    }
    en.boundary = std::move(b);
    entities.push_back(std::move(en));
  }
  d.entities = std::move(entities);
  const auto geometry = cad.geometry_model();
  for (auto& n : d.nodes) {
    if (!n.entity) continue;
    const EntityId gmsh_id = *n.entity;
    if (!remap(*n.entity))
      throw MeshingError(cad.name() + ": mesh node " + std::to_string(n.tag) + " at " +
                         point_text(Eigen::Vector3d(n.x[0], n.x[1], n.x[2])) + " is on Gmsh " + dim_word(gmsh_id.dim) +
                         " " + std::to_string(gmsh_id.tag) + ", which matches no entity of the model");
    // Every boundary node on the model at its parameters; where Gmsh's
    // parameters do not give its position (nodes added by the quad
    // subdivision), they are recomputed by projection.
    const Eigen::Vector3d x(n.x[0], n.x[1], n.x[2]);
    const int dim = n.entity->dim, tag = n.entity->tag;

    double err = 0;
    if (dim == 0) {
      err = (cad.vertex(tag) - x).norm();
      if (err > tol && err <= loose) {
        const Eigen::Vector3d y = cad.vertex(tag);
        n.x = {y[0], y[1], y[2]};
        err = 0.0;
      }
    } else if (dim == 1 || dim == 2) {
      auto at = [&] {
        return dim == 1 ? geometry.curve(tag)->evaluate(n.params[0])
                        : geometry.surface(tag)->evaluate({n.params[0], n.params[1]});
      };
      err = n.num_params == dim ? (at() - x).norm() : std::numeric_limits<double>::infinity();
      if (!(err <= tol)) {
        n.num_params = dim;
        if (dim == 1) {
          n.params[0] = geometry.curve(tag)->project(x);
        } else {
          const Eigen::Vector2d uv = geometry.surface(tag)->project(x);
          n.params[0] = uv[0];
          n.params[1] = uv[1];
        }
        err = (at() - x).norm();
        if (err > tol && err <= loose) {  // a subdivision node: onto the entity
          const Eigen::Vector3d y = at();
          n.x = {y[0], y[1], y[2]};
          err = 0.0;
        }
      }
    }
    if (!(err <= tol))
      throw MeshingError(cad.name() + ": mesh node " + std::to_string(n.tag) + " at " + point_text(x) + " is " +
                         std::to_string(err) + " off model " + dim_word(dim) + " " + std::to_string(tag) +
                         " (tolerance " + std::to_string(tol) + ")");
  }
  for (auto& e : d.elements)
    if (!remap(e.entity))
      throw MeshingError(cad.name() + ": mesh element " + std::to_string(e.tag) + " is on an unmatched Gmsh entity");
  // A volume mesh's boundary ears are split with their tetrahedra: the
  // flat-corner split of the curving pipeline (hom/mesh/flat_corners.hpp)
  // splits an interior edge, and an ear's third edge is on the boundary.
  if (!o.keep_ears && (o.dim == 3 || o.quads || o.split_triangle_ears)) {
    const FaceGeometry faces = face_geometry(geometry);
    if (o.quads)
      split_quad_ears(d, faces);
    else
      split_triangle_ears(d, faces);
  }
  if (!o.solids.empty()) keep_entities(d, solid_closure(cad, o.solids));
  return d;
}

std::vector<std::optional<CadPointClass>> classify_points(const CadModel& cad, const Eigen::Matrix3Xd& points,
                                                          double tolerance) {
  const auto& data = cad.data();
  std::vector<Box> edge_box(cad.num_edges()), face_box(cad.num_faces());
  for (int t = 1; t <= cad.num_edges(); ++t) edge_box[t - 1] = shape_box(data.edges(t), tolerance);
  for (int t = 1; t <= cad.num_faces(); ++t) face_box[t - 1] = shape_box(data.faces(t), tolerance);
  std::vector<std::optional<CadPointClass>> out(points.cols());
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Eigen::Vector3d x = points.col(i);
    std::optional<CadPointClass> best;
    auto offer = [&](CadPointClass c) {
      if (c.distance <= tolerance && (!best || c.distance < best->distance)) best = c;
    };
    for (int v = 1; v <= cad.num_vertices(); ++v) offer({{0, v}, 0, {}, (cad.vertex(v) - x).norm()});
    if (!best)
      for (int e = 1; e <= cad.num_edges(); ++e) {
        if (cad.degenerated(e) || !in_box(edge_box[e - 1], x)) continue;
        const auto c = cad.curve(e);
        const double t = c.project(x);
        offer({{1, e}, 1, {t, 0.0}, (c.evaluate(t) - x).norm()});
      }
    if (!best) {
      // Faces whose trimming holds the point first; else the nearest surface.
      std::optional<CadPointClass> outside;
      for (int f = 1; f <= cad.num_faces(); ++f) {
        if (!in_box(face_box[f - 1], x)) continue;
        const auto s = cad.surface(f);
        const Eigen::Vector2d uv = s.project(x);
        const CadPointClass c{{2, f}, 2, {uv[0], uv[1]}, (s.evaluate(uv) - x).norm()};
        if (s.contains(uv)) offer(c);
        else if (c.distance <= tolerance && (!outside || c.distance < outside->distance)) outside = c;
      }
      if (!best) best = outside;
    }
    out[i] = best;
  }
  return out;
}

}  // namespace hom::cad
