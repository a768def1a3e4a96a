#pragma once
/// @file edge_curve.hpp
/// The model curve an edge between two classified vertices lies on, from the
/// vertices' classification and the model's curve boundaries. Shared by
/// elevation (elevate.hpp: where an edge's high-order nodes go) and
/// boundary-layer insertion (boundary_layer.hpp: where a wall-border
/// midpoint goes), so that both classify an edge the same way.

#include <cstdlib>
#include <optional>

#include "hom/mesh/mesh.hpp"

namespace hom::detail {

/// Whether model vertex `point` bounds the model curve `curve` of `mesh`.
template <class MeshT>
bool curve_bounded_by(const MeshT& mesh, EntityId curve, int point) {
  const Entity* en = mesh.find_entity(curve);
  if (!en) return false;
  for (int b : en->boundary)
    if (std::abs(b) == point) return true;
  return false;
}

/// The curve (dimension-1 entity) the edge (a, b) lies on: both ends on one
/// curve; one on a curve and the other on a model vertex bounding it; both on
/// model vertices bounding exactly one curve. nullopt otherwise (ambiguous
/// included).
template <class MeshT>
std::optional<EntityId> common_curve(const MeshT& mesh, int a, int b) {
  const auto& ca = mesh.node_class(a).entity;
  const auto& cb = mesh.node_class(b).entity;
  if (!ca || !cb) return std::nullopt;
  if (ca->dim == 1 && cb->dim == 1) return ca == cb ? ca : std::nullopt;
  if (ca->dim == 1 && cb->dim == 0) return curve_bounded_by(mesh, *ca, cb->tag) ? ca : std::nullopt;
  if (ca->dim == 0 && cb->dim == 1) return curve_bounded_by(mesh, *cb, ca->tag) ? cb : std::nullopt;
  if (ca->dim == 0 && cb->dim == 0) {
    std::optional<EntityId> found;
    for (const auto& en : mesh.entities())
      if (en.id.dim == 1 && curve_bounded_by(mesh, en.id, ca->tag) && curve_bounded_by(mesh, en.id, cb->tag)) {
        if (found) return std::nullopt;  // ambiguous
        found = en.id;
      }
    return found;
  }
  return std::nullopt;
}

}  // namespace hom::detail
