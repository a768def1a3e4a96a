// hom_reference_report: the reference-element facts every other table rests on.
//
// For triangles, tetrahedra, quadrilaterals and hexahedra of degree p = 1..max:
//   - Lebesgue constant estimate (basis/lebesgue.hpp) of the equispaced nodes
//     and of the quasi-optimal set the thesis uses (appendix A: warp & blend on
//     simplices, tensor Gauss-Lobatto on cubes);
//   - 2-norm condition number of the nodal Vandermonde matrix of each set;
//   - number of quadrature points of the default rule and of the thesis rule
//     (6p - 3 on simplices; quadrature/quadrature_policy.hpp).
//
// Usage: hom_reference_report [--max-p N] [--json FILE]
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <boost/program_options.hpp>

#include "hom/basis/lagrange.hpp"
#include "hom/basis/lebesgue.hpp"
#include "hom/nodes/equispaced.hpp"
#include "hom/nodes/gauss_lobatto.hpp"
#include "hom/nodes/warp_blend.hpp"
#include "hom/quadrature/quadrature_policy.hpp"

#ifndef HOM_VERSION
#define HOM_VERSION "unknown (built without -DHOM_VERSION)"
#endif

namespace {

struct Row {
  std::string family;
  std::string quasi_optimal;
  int p = 0;
  int nodes = 0;
  double lebesgue_equispaced = 0, lebesgue_quasi_optimal = 0;
  double cond_equispaced = 0, cond_quasi_optimal = 0;
  int quad_default = 0, quad_thesis = 0;
  double time_s = 0;
};

std::string build_flags() {
  std::ostringstream s;
  s << "compiler: " <<
#if defined(__clang__)
      "clang "
#elif defined(__GNUC__)
      "gcc "
#endif
    << __VERSION__ << ", C++ " << __cplusplus;
#ifdef __OPTIMIZE__
  s << ", optimized";
#else
  s << ", not optimized";
#endif
#ifdef NDEBUG
  s << ", NDEBUG";
#else
  s << ", assertions on";
#endif
#ifdef __AVX512F__
  s << ", AVX-512";
#elif defined(__AVX2__)
  s << ", AVX2";
#elif defined(__AVX__)
  s << ", AVX";
#endif
#ifdef __FMA__
  s << "+FMA";
#endif
  s << "\nEigen " << EIGEN_WORLD_VERSION << "." << EIGEN_MAJOR_VERSION << "." << EIGEN_MINOR_VERSION
    << ", SIMD: " << Eigen::SimdInstructionSetsInUse();
  return s.str();
}

template <hom::ElementFamily F, hom::NodeSet Quasi>
void run_family(int max_p, std::vector<Row>& rows) {
  std::printf("\n%s (quasi-optimal set: %s)\n", std::string(F::name).c_str(), std::string(Quasi::name).c_str());
  std::printf("%3s %6s | %12s %12s | %12s %12s | %8s %8s\n", "p", "n_p", "Leb equi", "Leb q-opt", "cond equi",
              "cond q-opt", "#qp def", "#qp thes");
  for (int p = 1; p <= max_p; ++p) {
    const auto t0 = std::chrono::steady_clock::now();
    Row r;
    r.family = std::string(F::name);
    r.quasi_optimal = std::string(Quasi::name);
    r.p = p;
    r.nodes = F::num_nodes(p);
    {
      const hom::LagrangeBasis<F, hom::Equispaced> eq(p);
      r.lebesgue_equispaced = hom::lebesgue_constant(eq);
      r.cond_equispaced = eq.vandermonde_condition();
    }
    {
      const hom::LagrangeBasis<F, Quasi> qo(p);
      r.lebesgue_quasi_optimal = hom::lebesgue_constant(qo);
      r.cond_quasi_optimal = qo.vandermonde_condition();
    }
    r.quad_default = hom::quadrature_for<F, hom::DefaultExactness>(p).size();
    r.quad_thesis = hom::quadrature_for<F, hom::ThesisExactness>(p).size();
    r.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%3d %6d | %12.4g %12.4g | %12.4g %12.4g | %8d %8d\n", r.p, r.nodes, r.lebesgue_equispaced,
                r.lebesgue_quasi_optimal, r.cond_equispaced, r.cond_quasi_optimal, r.quad_default, r.quad_thesis);
    std::fflush(stdout);
    rows.push_back(r);
  }
}

void write_json(const std::string& path, const std::vector<Row>& rows) {
  // Write to a temporary file and rename, so a failure leaves no partial output.
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error("cannot write " + tmp);
    out.precision(10);
    out << "{\"tool\": \"hom_reference_report\", \"version\": \"" << HOM_VERSION << "\",\n"
        << " \"quadrature_default\": \"" << hom::DefaultExactness::name << "\",\n"
        << " \"quadrature_thesis\": \"" << hom::ThesisExactness::name << "\",\n \"cases\": [\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      out << "  {\"name\": \"" << r.family << "_p" << r.p << "\", \"family\": \"" << r.family << "\", \"p\": " << r.p
          << ", \"nodes\": " << r.nodes << ", \"quasi_optimal_nodes\": \"" << r.quasi_optimal
          << "\", \"lebesgue_equispaced\": " << r.lebesgue_equispaced
          << ", \"lebesgue_quasi_optimal\": " << r.lebesgue_quasi_optimal
          << ", \"cond_equispaced\": " << r.cond_equispaced << ", \"cond_quasi_optimal\": " << r.cond_quasi_optimal
          << ", \"quadrature_points_default\": " << r.quad_default
          << ", \"quadrature_points_thesis\": " << r.quad_thesis << ", \"time_s\": " << r.time_s << "}"
          << (i + 1 < rows.size() ? ",\n" : "\n");
    }
    out << " ]}\n";
    if (!out) throw std::runtime_error("error writing " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

int main(int argc, char** argv) {
  namespace po = boost::program_options;
  int max_p = 10;
  std::string json;
  po::options_description opts("hom_reference_report: Lebesgue constants, Vandermonde conditioning and "
                               "quadrature sizes of hom's reference elements\nOptions");
  opts.add_options()("help,h", "show this help")("max-p", po::value<int>(&max_p)->default_value(10),
                                                  "highest degree")(
      "json", po::value<std::string>(&json), "also write the table as JSON to this file");
  po::variables_map vm;
  try {
    po::store(po::parse_command_line(argc, argv, opts), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::cerr << "hom_reference_report: " << e.what() << "\n";
    return 2;
  }
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  if (max_p < 1 || max_p > 20) {
    std::cerr << "hom_reference_report: --max-p must be in [1, 20], got " << max_p << "\n";
    return 2;
  }

  std::printf("hom %s reference-element report\n%s\n", HOM_VERSION, build_flags().c_str());
  std::printf("Lebesgue constants: max of sum_j |N_j| over an equispaced lattice of degree ~3p plus 2000 random "
              "points (a lower bound, 2-3 digits).\ncond: 2-norm condition number of the Vandermonde matrix of "
              "the orthonormal basis at the nodes.\nquadrature points: default = %s; thesis = %s.\n",
              std::string(hom::DefaultExactness::name).c_str(), std::string(hom::ThesisExactness::name).c_str());

  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Row> rows;
  try {
    run_family<hom::Simplex<2>, hom::WarpBlend>(max_p, rows);
    run_family<hom::Simplex<3>, hom::WarpBlend>(max_p, rows);
    run_family<hom::Cube<2>, hom::GaussLobatto>(max_p, rows);
    run_family<hom::Cube<3>, hom::GaussLobatto>(max_p, rows);
    if (!json.empty()) write_json(json, rows);
  } catch (const std::exception& e) {
    std::cerr << "hom_reference_report: " << e.what() << "\n";
    return 1;
  }
  std::printf("\ntotal %.2f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}
