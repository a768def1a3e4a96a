// Gmsh model -> hom: MSH data of the current mesh and analytic geometry of
// the current model's entities (see gmsh_model.hpp).

#include "gmsh_model.hpp"

#include <gmsh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include <Eigen/Dense>

#include "hom/geometry/circle.hpp"
#include "hom/geometry/line.hpp"
#include "hom/geometry/plane.hpp"
#include "hom/geometry/sphere.hpp"
#include "meshing_error.hpp"

namespace hom::meshing {

namespace {

int session_count = 0;
std::terminate_handler previous_terminate = nullptr;
std::string meshed_subject;  // GmshSessionOptions::subject of the innermost session

// See GmshSession: reports the exception that reached std::terminate (Gmsh
// throws its messages as std::string) and exits with status 1.
[[noreturn]] void report_gmsh_failure() {
  std::string what = "an unknown error";
  if (const auto e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::string& message) {
      what = message;
    } catch (const std::exception& error) {
      what = error.what();
    } catch (...) {
    }
  }
  std::fflush(stdout);  // the progress printed so far, before the error
  std::fprintf(stderr, "hom: %s: Gmsh failed: %s (inside its parallel meshing loop, where it cannot be recovered)\n",
               meshed_subject.empty() ? "meshing" : meshed_subject.c_str(), what.c_str());
  std::_Exit(1);
}

}  // namespace

// Waits for the session's end or its time limit, whichever comes first; at
// the limit Gmsh is still inside a call that cannot be interrupted, so the
// process ends (nothing after meshing has run, so no output file is begun).
struct GmshSession::Watchdog {
  std::mutex mutex;
  std::condition_variable session_over;
  bool over = false;
  std::thread thread;

  Watchdog(double seconds, std::string subject) {
    thread = std::thread([this, seconds, subject = std::move(subject)] {
      std::unique_lock lock(mutex);
      if (session_over.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return over; })) return;
      std::fflush(stdout);
      std::fprintf(stderr,
                   "hom: %s: Gmsh did not finish meshing within %g s (Gmsh 4.8 loops forever on some surfaces, "
                   "a cone's apex for one)\n",
                   subject.empty() ? "meshing" : subject.c_str(), seconds);
      std::_Exit(1);
    });
  }
  ~Watchdog() {
    {
      const std::lock_guard lock(mutex);
      over = true;
    }
    session_over.notify_one();
    thread.join();
  }
};

GmshSession::GmshSession(const GmshSessionOptions& options) : previous_subject_(meshed_subject) {
  if (options.time_limit_s < 0 || !std::isfinite(options.time_limit_s))
    throw std::invalid_argument("hom::meshing::GmshSession: the time limit must be finite and >= 0");
  if (options.time_limit_s > 0) watchdog_ = std::make_unique<Watchdog>(options.time_limit_s, options.subject);
  if (!options.subject.empty()) meshed_subject = options.subject;
  if (session_count++ == 0) {
    previous_terminate = std::set_terminate(report_gmsh_failure);
    gmsh_call([] { gmsh::initialize(0, nullptr, false); });
  }
  gmsh_call([&] {
    gmsh::option::setNumber("General.Terminal", options.verbose ? 1 : 0);
    gmsh::option::setNumber("General.NumThreads", options.threads);
  });
}

GmshSession::~GmshSession() {
  watchdog_.reset();
  meshed_subject = previous_subject_;
  if (--session_count == 0) {
    try {
      gmsh::finalize();
    } catch (...) {  // a destructor must not throw; Gmsh is gone either way
    }
    std::set_terminate(previous_terminate);
  }
}

io::MshData gmsh_model_data(const std::string& name) {
  io::MshData d;
  d.path = name;
  gmsh_call([&] {
    gmsh::vectorpair groups;
    gmsh::model::getPhysicalGroups(groups);
    for (const auto& [dim, tag] : groups) {
      std::string pname;
      gmsh::model::getPhysicalName(dim, tag, pname);
      d.physical_names.push_back(PhysicalGroup{dim, tag, pname});
    }

    gmsh::vectorpair entities;
    gmsh::model::getEntities(entities);
    for (const auto& [dim, tag] : entities) {
      Entity en;
      en.id = EntityId{dim, tag};
      gmsh::model::getPhysicalGroupsForEntity(dim, tag, en.physical_tags);
      if (dim > 0) {
        gmsh::vectorpair bnd;
        gmsh::model::getBoundary({{dim, tag}}, bnd, false, true, false);
        for (const auto& b : bnd) en.boundary.push_back(b.second);
      }
      d.entities.push_back(std::move(en));

      std::vector<std::size_t> node_tags;
      std::vector<double> coord, params;
      gmsh::model::mesh::getNodes(node_tags, coord, params, dim, tag, false, true);
      const std::size_t nn = node_tags.size();
      const int np = nn && params.size() == nn * std::size_t(dim) && dim <= 2 ? dim : 0;
      for (std::size_t i = 0; i < nn; ++i) {
        io::MshNode n;
        n.tag = static_cast<std::int64_t>(node_tags[i]);
        n.x = {coord[3 * i], coord[3 * i + 1], coord[3 * i + 2]};
        n.entity = EntityId{dim, tag};
        n.num_params = np;
        for (int k = 0; k < np; ++k) n.params[k] = params[np * i + k];
        d.nodes.push_back(n);
      }

      std::vector<int> types;
      std::vector<std::vector<std::size_t>> elem_tags, elem_nodes;
      gmsh::model::mesh::getElements(types, elem_tags, elem_nodes, dim, tag);
      for (std::size_t t = 0; t < types.size(); ++t) {
        const std::size_t ne = elem_tags[t].size();
        if (ne == 0) continue;
        const int per = static_cast<int>(elem_nodes[t].size() / ne);
        for (std::size_t e = 0; e < ne; ++e) {
          io::MshElement el;
          el.tag = static_cast<std::int64_t>(elem_tags[t][e]);
          el.type = types[t];
          el.entity = EntityId{dim, tag};
          el.first = d.element_nodes.size();
          el.num_nodes = per;
          for (int k = 0; k < per; ++k)
            d.element_nodes.push_back(static_cast<std::int64_t>(elem_nodes[t][e * per + k]));
          d.elements.push_back(el);
        }
      }
    }
  });
  return d;
}

namespace {

Eigen::Vector3d value(int dim, int tag, const std::vector<double>& params) {
  std::vector<double> x;
  gmsh::model::getValue(dim, tag, params, x);
  return {x.at(0), x.at(1), x.at(2)};
}

// Points of the entity's parameterization on an n (x n) grid over its bounds.
std::vector<Eigen::Vector3d> samples(int dim, int tag, int n) {
  std::vector<double> lo, hi;
  gmsh::model::getParametrizationBounds(dim, tag, lo, hi);
  std::vector<Eigen::Vector3d> out;
  if (dim == 1) {
    for (int i = 0; i <= n; ++i) out.push_back(value(1, tag, {lo[0] + (hi[0] - lo[0]) * i / n}));
  } else {
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j)
        out.push_back(value(2, tag, {lo[0] + (hi[0] - lo[0]) * i / n, lo[1] + (hi[1] - lo[1]) * j / n}));
  }
  return out;
}

double extent(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::Vector3d lo = pts.front(), hi = pts.front();
  for (const auto& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

// Sphere through points: |x|^2 = 2 c.x + (r^2 - |c|^2), linear least squares.
std::optional<Sphere> fit_sphere(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::MatrixXd A(pts.size(), 4);
  Eigen::VectorXd b(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    A.row(i) << 2 * pts[i].transpose(), 1.0;
    b[i] = pts[i].squaredNorm();
  }
  const Eigen::Vector4d s = A.colPivHouseholderQr().solve(b);
  const Eigen::Vector3d c = s.head<3>();
  const double r2 = s[3] + c.squaredNorm();
  if (!(r2 > 0)) return std::nullopt;
  return Sphere(c, std::sqrt(r2));
}

// Circle through three points of the curve (its two ends and its middle are
// distinct on a proper arc).
std::optional<Circle<3>> fit_circle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a;
  const Eigen::Vector3d n = ab.cross(ac);
  if (!(n.norm() > 1e-14 * ab.norm() * ac.norm())) return std::nullopt;
  // Circumcentre: a + (|ac|^2 (n x ab) ... ) / (2 |n|^2), the standard formula.
  const Eigen::Vector3d center =
      a + (ac.squaredNorm() * n.cross(ab) + ab.squaredNorm() * ac.cross(n)) / (2.0 * n.squaredNorm());
  return Circle<3>(center, (a - center).norm(), n);
}

}  // namespace

GeometryModel<3> analytic_geometry_from_gmsh_model(double tolerance) {
  GeometryModel<3> model;
  gmsh_call([&] {
    for (int dim : {1, 2}) {
      gmsh::vectorpair entities;
      gmsh::model::getEntities(entities, dim);
      for (const auto& [d, tag] : entities) {
        std::string type;
        gmsh::model::getType(d, tag, type);
        const auto pts = samples(d, tag, 8);
        const double size = extent(pts);
        if (!(size > 0)) continue;
        auto fits = [&](const auto& g) {
          for (const auto& p : pts)
            if ((g.evaluate(g.project(p)) - p).norm() > tolerance * size) return false;
          return true;
        };
        if (d == 1 && type == "Line") {
          const Line<3> g(pts.front(), pts.back());
          if (fits(g)) model.add_curve(tag, g);
        } else if (d == 1 && type == "Circle") {
          if (auto g = fit_circle(pts.front(), pts[pts.size() / 2], pts.back()); g && fits(*g))
            model.add_curve(tag, *g);
          else if (auto g2 = fit_circle(pts[0], pts[pts.size() / 3], pts[2 * pts.size() / 3]); g2 && fits(*g2))
            model.add_curve(tag, *g2);  // a full circle: its two ends coincide
        } else if (d == 2 && type == "Plane") {
          std::vector<double> lo, hi, normal;
          gmsh::model::getParametrizationBounds(2, tag, lo, hi);
          const std::vector<double> mid{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2};
          gmsh::model::getNormal(tag, mid, normal);
          const Plane g(value(2, tag, mid), Eigen::Vector3d(normal.at(0), normal.at(1), normal.at(2)));
          if (fits(g)) model.add_surface(tag, g);
        } else if (d == 2 && type == "Sphere") {
          if (auto g = fit_sphere(pts); g && fits(*g)) model.add_surface(tag, *g);
        }
      }
    }
  });
  return model;
}

}  // namespace hom::meshing
