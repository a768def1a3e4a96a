#pragma once
/// @file boundary_layer_report.hpp
/// How `hom boundary-layer` and `hom curve --bl-first` tell the stages of the
/// boundary-layer pipeline (optimize/boundary_layer_pipeline.hpp): table
/// 6.4's rows on stdout, and one JSON case per stage (DESIGN.md schema) with
/// the layer's parameters and the ideal layer mesh's largest aspect ratio.

#include <cstdio>
#include <string>
#include <vector>

#include "hom/io/report.hpp"
#include "hom/optimize/boundary_layer_pipeline.hpp"
#include "mesh_io.hpp"

namespace hom::tools {

/// Why the degree-p stages were not run, for a result that stopped at (c).
template <int Dim>
std::string smoothed_tangled_message(const BoundaryLayerPipelineResult<Dim>& r) {
  return "the linear mesh smoothed against the stretched ideal (stage c) still has " +
         std::to_string(r.stages.back().quality.inverted) + " inverted elements after " +
         std::to_string(r.stages.back().iterations) +
         " iterations, so stages (d) and (e) were not run (they cannot end valid); the layer may be too thick for "
         "the elements at the wall: try a smaller first height, growth or number of layers, or a finer mesh there";
}

inline void print_boundary_layer_stages(const std::vector<BoundaryLayerStage>& stages) {
  std::printf("  %-10s %2s %8s %8s %7s %7s %7s %8s %6s %5s %8s\n", "stage", "p", "#elems", "#nodes", "Min", "Max", "Mean",
              "Std.Dev.", "#inv", "iter", "time[s]");
  for (const auto& s : stages)
    std::printf("  %-10s %2d %8d %8d %7.4f %7.4f %7.4f %8.4f %6d %5d %8.3f\n", s.name.c_str(), s.p, s.elements, s.nodes,
                s.quality.min, s.quality.max, s.quality.mean, s.quality.std_dev, s.quality.inverted, s.iterations,
                s.time_s);
}

/// The result for ParaView: each element's quality against the last stage's
/// ideal (the smoothed linear mesh, or the stretched ideal when the pipeline
/// stopped at a tangled stage (c)) and its layer level (-1 outside).
template <int Dim>
void write_boundary_layer_vtu(const std::string& path, const BoundaryLayerPipelineResult<Dim>& r) {
  const auto q = mesh_quality(r.mesh, ShapeMeasure{}, r.final_ideal(),
                              quadrature_for<Simplex<Dim>, DefaultExactness>(r.mesh.degree()));
  std::vector<double> layer_level(r.mesh.num_elements(), -1.0);
  for (int e = 0; e < r.mesh.num_elements(); ++e)
    if (r.layer.level[e]) layer_level[e] = *r.layer.level[e];
  io::VtuOptions vo;
  vo.interpolate_point_data = false;
  io::write_vtu(path, r.mesh, {node_kind_field(r.mesh)}, {{"quality", 1, q.qualities()}, {"layer_level", 1, layer_level}},
                vo);
}

/// One case per stage; `source` names the input (a mesh file or a model).
template <int Dim>
std::vector<io::Json> boundary_layer_cases(const std::string& source, const BoundaryLayerPipelineResult<Dim>& r,
                                           const BoundaryLayerOptions& layer) {
  std::vector<io::Json> cases;
  for (const auto& s : r.stages) {
    io::CaseHeader h{source, std::string(Simplex<Dim>::name), s.p, s.elements, s.nodes, s.name, "shape", s.ideal};
    auto c = io::quality_case(h, s.quality, s.scaled_jacobian);
    c.set("time_s", s.time_s)
        .set("iterations", s.iterations)
        .set("aspect_ratio", r.layer.max_aspect_ratio)
        .set("layers", layer.layers)
        .set("first_height", layer.first_height)
        .set("growth", layer.growth);
    if (!s.stop_reason.empty()) c.set("stop_reason", s.stop_reason).set("converged", s.converged);
    cases.push_back(std::move(c));
  }
  return cases;
}

}  // namespace hom::tools
