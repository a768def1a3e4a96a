#pragma once
/// @file geometry_model.hpp
/// The geometry of a mesh's model entities, looked up at run time by entity
/// tag: AnyCurve and AnySurface hold any CurveGeometry / SurfaceGeometry
/// behind one type (the entities of one model are of many kinds), and
/// GeometryModel maps curve tags (dimension 1) and surface tags (dimension 2)
/// to them.
///
///   hom::GeometryModel<3> model;
///   model.add_surface(7, hom::Sphere({2.5, 2.5, 2.5}, 0.5));
///   model.add_surface(1, hom::Plane({0, 0, 0}, {-1, 0, 0}));
///
/// The erased objects are shared (copying a model is cheap) and immutable, so
/// one model can be read from several threads.

#include <concepts>
#include <map>
#include <memory>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

#include "hom/geometry/boundary_geometry.hpp"
#include "hom/mesh/mesh.hpp"

namespace hom {

/// A CurveGeometry of the given space dimension, type-erased; itself a
/// CurveGeometry.
template <int SpaceDim>
class AnyCurve {
 public:
  static constexpr int space_dim = SpaceDim;
  using Point = Eigen::Matrix<double, SpaceDim, 1>;

  template <CurveGeometry G>
    requires(G::space_dim == SpaceDim && !std::same_as<std::remove_cvref_t<G>, AnyCurve>)
  AnyCurve(G g) : impl_(std::make_shared<Model<G>>(std::move(g))) {}  // NOLINT: implicit on purpose

  Point evaluate(double u) const { return impl_->evaluate(u); }
  Point derivative(double u) const { return impl_->derivative(u); }
  Point second_derivative(double u) const { return impl_->second_derivative(u); }
  double project(const Point& x) const { return impl_->project(x); }
  ParameterRange range() const { return impl_->range(); }

 private:
  struct Concept {
    virtual ~Concept() = default;
    virtual Point evaluate(double u) const = 0;
    virtual Point derivative(double u) const = 0;
    virtual Point second_derivative(double u) const = 0;
    virtual double project(const Point& x) const = 0;
    virtual ParameterRange range() const = 0;
  };
  template <class G>
  struct Model final : Concept {
    explicit Model(G g) : g(std::move(g)) {}
    Point evaluate(double u) const override { return g.evaluate(u); }
    Point derivative(double u) const override { return g.derivative(u); }
    Point second_derivative(double u) const override { return g.second_derivative(u); }
    double project(const Point& x) const override { return g.project(x); }
    ParameterRange range() const override { return g.range(); }
    G g;
  };
  std::shared_ptr<const Concept> impl_;
};

/// A SurfaceGeometry, type-erased; itself a SurfaceGeometry.
class AnySurface {
 public:
  template <SurfaceGeometry G>
    requires(!std::same_as<std::remove_cvref_t<G>, AnySurface>)
  AnySurface(G g) : impl_(std::make_shared<Model<G>>(std::move(g))) {}  // NOLINT: implicit on purpose

  Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const { return impl_->evaluate(uv); }
  Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const { return impl_->derivatives(uv); }
  SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const { return impl_->second_derivatives(uv); }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const { return impl_->project(x); }
  ParameterRange range(int k) const { return impl_->range(k); }

 private:
  struct Concept {
    virtual ~Concept() = default;
    virtual Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const = 0;
    virtual Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const = 0;
    virtual SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const = 0;
    virtual Eigen::Vector2d project(const Eigen::Vector3d& x) const = 0;
    virtual ParameterRange range(int k) const = 0;
  };
  template <class G>
  struct Model final : Concept {
    explicit Model(G g) : g(std::move(g)) {}
    Eigen::Vector3d evaluate(const Eigen::Vector2d& uv) const override { return g.evaluate(uv); }
    Eigen::Matrix<double, 3, 2> derivatives(const Eigen::Vector2d& uv) const override { return g.derivatives(uv); }
    SurfaceSecondDerivatives second_derivatives(const Eigen::Vector2d& uv) const override {
      return g.second_derivatives(uv);
    }
    Eigen::Vector2d project(const Eigen::Vector3d& x) const override { return g.project(x); }
    ParameterRange range(int k) const override { return g.range(k); }
    G g;
  };
  std::shared_ptr<const Concept> impl_;
};

static_assert(CurveGeometry<AnyCurve<2>>);
static_assert(CurveGeometry<AnyCurve<3>>);
static_assert(SurfaceGeometry<AnySurface>);

/// Geometry of the curve (dimension 1) and surface (dimension 2) entities of
/// a model in R^SpaceDim, by tag. Entities without geometry are simply absent
/// (their nodes keep their positions).
template <int SpaceDim>
class GeometryModel {
  static_assert(SpaceDim == 2 || SpaceDim == 3, "hom::GeometryModel: SpaceDim must be 2 or 3");

 public:
  /// Sets (or replaces) the geometry of curve `tag`.
  void add_curve(int tag, AnyCurve<SpaceDim> g) { curves_.insert_or_assign(tag, std::move(g)); }
  /// Sets (or replaces) the geometry of surface `tag` (3D models only).
  void add_surface(int tag, AnySurface g)
    requires(SpaceDim == 3)
  {
    surfaces_.insert_or_assign(tag, std::move(g));
  }

  const AnyCurve<SpaceDim>* curve(int tag) const {
    auto it = curves_.find(tag);
    return it == curves_.end() ? nullptr : &it->second;
  }
  const AnySurface* surface(int tag) const {
    auto it = surfaces_.find(tag);
    return it == surfaces_.end() ? nullptr : &it->second;
  }
  /// Whether the entity (dimension 1 or 2) has a geometry.
  bool has(EntityId id) const { return (id.dim == 1 && curve(id.tag)) || (id.dim == 2 && surface(id.tag)); }

  const std::map<int, AnyCurve<SpaceDim>>& curves() const { return curves_; }
  const std::map<int, AnySurface>& surfaces() const { return surfaces_; }

 private:
  std::map<int, AnyCurve<SpaceDim>> curves_;
  std::map<int, AnySurface> surfaces_;
};

}  // namespace hom
