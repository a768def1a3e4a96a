// hom quality MESH [--measure shape|oddy] [--ideal straight|equilateral]
//                  [--quadrature default|thesis] [--certify [--certify-depth N]]
//                  [--vtu OUT.vtu] [--json FILE]
//
// Validates a high-order mesh (chapter 3): prints the thesis's statistics
// table of the element quality q_E (definition 3.6) and of the scaled
// Jacobian, and optionally writes a VTU colored by element and point-wise
// quality with the invalid elements flagged.
//
// Surface meshes (triangles or quadrilaterals with nodes off z = 0) get the
// surface measure of chapter 5 (J-bar of eq 5.5, definitions 5.1-5.2), from
// the 3D node coordinates alone: the ideal is each element's straight-sided
// facet (or the equilateral triangle / unit square), and an element is invalid
// where its curved tangent plane turns over with respect to the normal of its
// own straight-sided facet (no geometry is needed, so an element whose facet
// itself is flipped with respect to its neighbours is not detected).
//
// --certify (planar and volume meshes) adds the certificate of
// quality/certify.hpp: the sign of det D phi_P everywhere in each element from
// Bernstein bounds with adaptive subdivision, not only at quadrature points.

#include <cstdio>
#include <iostream>
#include <string>

#include <boost/program_options.hpp>

#include "certify_options.hpp"
#include "command.hpp"
#include "hom/io/report.hpp"
#include "hom/measure/oddy_measure.hpp"
#include "hom/measure/shape_measure.hpp"
#include "hom/quality/certify.hpp"
#include "hom/quality/mesh_quality.hpp"
#include "hom/surface/surface_mesh_quality.hpp"
#include "mesh_io.hpp"
#include "options.hpp"
#include "replaced_ideals_note.hpp"

namespace po = boost::program_options;

namespace {

struct QualityOptions {
  std::string path;
  std::string measure = "shape";
  std::string ideal = "straight";
  std::string quadrature = "default";
  std::string vtu;
  std::string json;
  hom::tools::CertifyCli certify;  // --certify-rounds not declared: quality only certifies
};

void print_row(const char* label, const hom::Statistics& s) {
  std::printf("  %-16s %8.4f %8.4f %8.4f %9.4f %6d\n", label, s.min, s.max, s.mean, s.std_dev, s.inverted);
}

template <class MeshT, class Measure>
int report(const MeshT& mesh, const Measure& measure, const QualityOptions& o) {
  using F = typename MeshT::family;
  constexpr bool surface = MeshT::space_dim != MeshT::dim;
  const hom::IdealKind ideal = hom::parse_ideal_kind(o.ideal);
  const auto& rule = o.quadrature == "thesis" ? hom::quadrature_for<F, hom::ThesisExactness>(mesh.degree())
                                              : hom::quadrature_for<F, hom::DefaultExactness>(mesh.degree());
  hom::MeshQuality q;
  if constexpr (surface)
    q = hom::surface_mesh_quality(mesh, measure, ideal, rule);
  else
    q = hom::mesh_quality(mesh, measure, ideal, rule);
  const hom::Statistics qs = q.quality_statistics(), sj = q.scaled_jacobian_statistics();
  const std::string ideal_name = ideal == hom::IdealKind::regular ? "equilateral" : "straight-sided";

  std::printf("%s: %s%s of degree %d, %d elements, %d nodes\n", o.path.c_str(), surface ? "surface mesh, " : "",
              std::string(F::name).c_str(), mesh.degree(), mesh.num_elements(), mesh.num_nodes());
  if (surface)
    std::printf("surface measure (chapter 5, eq 5.5), oriented by each element's straight-sided facet\n");
  std::printf("measure %s, ideal %s, quadrature %s (exact to degree %d, %d points per element)\n",
              std::string(Measure::name).c_str(), ideal_name.c_str(), o.quadrature.c_str(), rule.exactness, rule.size());
  if constexpr (!surface) {
    if (ideal != hom::IdealKind::regular) hom::tools::print_replaced_ideals_note(hom::count_replaced_ideals(mesh));
  }
  std::printf("\n");
  std::printf("  %-16s %8s %8s %8s %9s %6s\n", "", "Min", "Max", "Mean", "Std.Dev.", "#inv");
  print_row("quality", qs);
  print_row("scaled Jacobian", sj);
  std::printf("\nmesh quality q_M = %.6f (eq 3.26%s); %s\n", q.mesh_quality, surface ? ", defs. 5.1-5.2" : "",
              q.inverted() ? "INVALID: some elements have det <= 0 at a quadrature point" : "valid at every quadrature point");

  // Certificate (planar and volume meshes): sign of det everywhere in each element.
  std::vector<double> status;
  hom::io::Json::Object certified;  // the certificate's JSON keys
  bool certified_ok = true;
  if (o.certify.on) {
    if constexpr (surface) {
      std::printf("\n--certify: certification covers planar and volume meshes; skipped for this surface mesh\n");
    } else {
      hom::CertifyOptions co;
      co.max_depth = o.certify.depth;
      const auto c = hom::certify_mesh(mesh, co);
      std::printf("\ncertified (Bernstein bounds of det D phi_P, subdivision depth <= %d, deepest used %d):\n",
                  co.max_depth, c.max_depth);
      std::printf("  %d certified valid, %d certified invalid, %d undecided; certified min scaled Jacobian >= %.4f\n",
                  c.valid, c.invalid, c.undecided, c.min_scaled_jacobian);
      int shown = 0;
      for (int e = 0; e < mesh.num_elements() && shown < 5; ++e) {
        const auto& ec = c.elements[e];
        if (ec.status == hom::Certificate::certified_valid) continue;
        ++shown;
        if (ec.invalid_point) {
          const auto x = mesh.map(e, *ec.invalid_point);
          std::printf("  element %d: det = %.3g <= 0 at (", e, ec.invalid_value);
          for (int a = 0; a < x.size(); ++a) std::printf(a ? ", %.6g" : "%.6g", x[a]);
          std::printf(")\n");
        } else {
          std::printf("  element %d: undecided (det bounds [%.3g, %.3g] at depth %d)\n", e, ec.min_det_bound,
                      ec.max_det_bound, ec.depth);
        }
      }
      certified_ok = c.invalid == 0 && c.undecided == 0;
      status = c.status_codes();
      certified = {{"certified_valid", c.valid},
                   {"certified_invalid", c.invalid},
                   {"undecided", c.undecided},
                   {"certified_min_scaled_jacobian", c.min_scaled_jacobian},
                   {"certify_max_depth", co.max_depth}};
    }
  }

  if (!o.vtu.empty()) {
    std::vector<double> inverted, sjac;
    for (const auto& e : q.elements) {
      inverted.push_back(e.valid ? 0.0 : 1.0);
      sjac.push_back(e.scaled_jacobian());
    }
    hom::io::VtuOptions vo;
    vo.interpolate_point_data = false;
    std::vector<double> nodal;
    if constexpr (surface)
      nodal = hom::surface_nodal_mesh_quality(mesh, measure, ideal, rule);
    else
      nodal = hom::nodal_mesh_quality(mesh, measure, ideal, rule);
    std::vector<hom::io::VtuField> cells{
        {"quality", 1, q.qualities()}, {"scaled_jacobian", 1, sjac}, {"inverted", 1, inverted}};
    // 0 certified valid, 1 undecided, 2 certified invalid (hom::status_code).
    if (!status.empty()) cells.push_back({"certificate", 1, status});
    hom::io::write_vtu(o.vtu, mesh, {{"pointwise_quality", 1, std::move(nodal)}}, cells, vo);
    std::printf("wrote %s\n", o.vtu.c_str());
  }
  if (!o.json.empty()) {
    hom::io::CaseHeader h{o.path, std::string(F::name), mesh.degree(), mesh.num_elements(), mesh.num_nodes(),
                          "input", std::string(Measure::name), ideal_name};
    auto c = hom::io::quality_case(h, qs, sj);
    c.set("mesh_quality", q.mesh_quality).set("quadrature_exactness", rule.exactness).set("surface", surface);
    for (auto& [k, v] : certified) c.set(k, std::move(v));
    hom::io::write_report(o.json, "hom quality", HOM_VERSION, {std::move(c)});
  }
  return q.inverted() || !certified_ok ? 3 : 0;
}

int run(int argc, char** argv) {
  QualityOptions o;
  po::options_description opts(
      "hom quality MESH [options]\n\n"
      "Validate a high-order mesh: element quality q_E (thesis def. 3.6) and scaled Jacobian\n"
      "statistics. Surface meshes (triangles/quadrilaterals in 3D) use the surface measure of\n"
      "chapter 5 (defs. 5.1-5.2). Exit status 0 when every element is valid, 3 when some are invalid\n"
      "(with --certify: also when some element is certified invalid or undecided).\n\noptions");
  opts.add_options()("help,h", "show this help")                                                       //
      ("measure", po::value(&o.measure)->default_value("shape"), "distortion measure: shape | oddy")  //
      ("ideal", po::value(&o.ideal)->default_value("straight"),
       "ideal element: straight (each element's straight-sided counterpart) | equilateral")  //
      ("quadrature", po::value(&o.quadrature)->default_value("default"),
       "quadrature: default | thesis (exact to degree 6p-3)")                                   //
      ("vtu", po::value(&o.vtu), "write a VTU colored by quality (ParaView)")                    //
      ("json", po::value(&o.json), "write the statistics as JSON");
  o.certify.declare(opts,
                    "certify the sign of det everywhere in each element (Bernstein bounds, adaptive subdivision): "
                    "#certified valid / invalid / undecided and a certified lower bound of the scaled Jacobian",
                    /*repair=*/false);
  po::variables_map vm;
  if (!hom::tools::parse_options("quality", argc, argv, opts, {{"mesh", po::value(&o.path)}}, vm)) return 0;
  if (o.path.empty()) throw hom::tools::UsageError("quality: need a mesh file (see 'hom quality --help')");
  if (o.measure != "shape" && o.measure != "oddy")
    throw hom::tools::UsageError("quality: --measure must be shape or oddy, got '" + o.measure + "'");
  if (o.quadrature != "default" && o.quadrature != "thesis")
    throw hom::tools::UsageError("quality: --quadrature must be default or thesis, got '" + o.quadrature + "'");
  try {
    hom::parse_ideal_kind(o.ideal);
  } catch (const std::invalid_argument& e) {
    throw hom::tools::UsageError(std::string("quality: ") + e.what());
  }
  o.certify.check("quality");
  if (!o.vtu.empty() && !hom::tools::ends_with(o.vtu, ".vtu"))
    throw hom::tools::UsageError("quality: --vtu file name must end in .vtu");

  const auto data = hom::io::read_msh_data(o.path);
  return hom::tools::with_mesh<hom::WarpBlend>(data, [&](auto& mesh) -> int {
    if (o.measure == "oddy") return report(mesh, hom::OddyMeasure{}, o);
    return report(mesh, hom::ShapeMeasure{}, o);
  });
}

const hom::tools::RegisterCommand reg{{"quality", "Validate a mesh: quality and scaled-Jacobian statistics", run}};

}  // namespace
