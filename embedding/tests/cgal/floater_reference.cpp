// The reference for ntori's Floater map (embedding/src/floater.rs): CGAL's mean value coordinates
// parameterizer (Surface_mesh_parameterization::Mean_value_coordinates_parameterizer_3) on the same
// triangulated disk, its boundary held at the same given positions. Built and run by
// embedding/tests/reference.rs.
//
//   floater_reference [lu|bicgstab] < input > output
//
// Input (whitespace separated; numbers as Rust writes them, which round-trip exactly):
//   V T P
//   x y z        V lines: the vertices
//   a b c        T lines: counter-clockwise triangles, vertex indices from 0
//   v u w        P lines: a boundary vertex and its fixed position (u, w)
// The pinned vertices must be exactly the disk's boundary (CGAL pins its whole border and nothing
// else; a mismatch is an error, not a different problem solved quietly).
//
// Output: V lines "u v" with %.17g, every vertex in input order.
//
// The solver: "lu" (the default here) is Eigen's direct SparseLU, so both sides solve the same
// linear system exactly up to rounding. "bicgstab" is CGAL's own default (BiCGSTAB with an
// incomplete LU preconditioner, Eigen's default tolerance), kept to measure how far that lands.

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/Error_code.h>
#include <CGAL/Surface_mesh_parameterization/Mean_value_coordinates_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <CGAL/Eigen_solver_traits.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseLU>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace SMP = CGAL::Surface_mesh_parameterization;

using Kernel = CGAL::Simple_cartesian<double>;
using Point_2 = Kernel::Point_2;
using Point_3 = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point_3>;
using vertex_descriptor = Mesh::Vertex_index;
using halfedge_descriptor = Mesh::Halfedge_index;

// A border parameterizer (CGAL's BorderParameterizer_3 concept) that puts every border vertex at
// the position it was given, instead of spacing the border around a circle or a square.
struct Given_border {
  const std::vector<Point_2>* pins;  // by vertex index
  const std::vector<bool>* pinned;

  template <typename VertexUVmap, typename VertexIndexMap, typename VertexParameterizedMap>
  SMP::Error_code parameterize(const Mesh& mesh, halfedge_descriptor bhd, VertexUVmap uvmap,
                               VertexIndexMap, VertexParameterizedMap vpmap) {
    for (halfedge_descriptor h : CGAL::halfedges_around_face(bhd, mesh)) {
      vertex_descriptor v = CGAL::source(h, mesh);
      if (!(*pinned)[v.idx()]) return SMP::ERROR_BORDER_TOO_SHORT;  // caught below, with a message
      put(uvmap, v, (*pins)[v.idx()]);
      put(vpmap, v, true);
    }
    return SMP::OK;
  }

  // The caller's promise (ntori's tests pin to convex polygons); CGAL only uses it to skip a check.
  bool is_border_convex() const { return true; }
};

using Eigen_matrix = CGAL::Eigen_sparse_matrix<double>::EigenType;
using Direct = CGAL::Eigen_solver_traits<Eigen::SparseLU<Eigen_matrix, Eigen::COLAMDOrdering<int>>>;
using Iterative =
    CGAL::Eigen_solver_traits<Eigen::BiCGSTAB<Eigen_matrix, Eigen::IncompleteLUT<double>>>;

static int fail(const std::string& why) {
  std::cerr << "floater_reference: " << why << "\n";
  return 1;
}

template <typename Solver>
static SMP::Error_code run(Mesh& mesh, Given_border border, halfedge_descriptor bhd,
                           Mesh::Property_map<vertex_descriptor, Point_2> uv) {
  SMP::Mean_value_coordinates_parameterizer_3<Mesh, Given_border, Solver> parameterizer(border);
  return SMP::parameterize(mesh, parameterizer, bhd, uv);
}

int main(int argc, char** argv) {
  const std::string solver = argc > 1 ? argv[1] : "lu";
  if (solver != "lu" && solver != "bicgstab") return fail("the solver is lu or bicgstab");

  std::size_t nv = 0, nt = 0, np = 0;
  if (!(std::cin >> nv >> nt >> np)) return fail("no header (V T P)");
  Mesh mesh;
  for (std::size_t i = 0; i < nv; ++i) {
    double x, y, z;
    if (!(std::cin >> x >> y >> z)) return fail("a vertex is missing");
    mesh.add_vertex(Point_3(x, y, z));
  }
  for (std::size_t i = 0; i < nt; ++i) {
    std::size_t a, b, c;
    if (!(std::cin >> a >> b >> c) || a >= nv || b >= nv || c >= nv)
      return fail("triangle " + std::to_string(i) + " is missing or refers to a missing vertex");
    // add_face refuses a face that would make the mesh non-manifold or misoriented.
    if (mesh.add_face(vertex_descriptor(a), vertex_descriptor(b), vertex_descriptor(c)) ==
        Mesh::null_face())
      return fail("triangle " + std::to_string(i) + " cannot be added (not an oriented manifold)");
  }
  std::vector<Point_2> pins(nv, Point_2(0, 0));
  std::vector<bool> pinned(nv, false);
  for (std::size_t i = 0; i < np; ++i) {
    std::size_t v;
    double u, w;
    if (!(std::cin >> v >> u >> w) || v >= nv) return fail("a pin is missing or out of range");
    pins[v] = Point_2(u, w);
    pinned[v] = true;
  }

  // The disk's one border: find a border halfedge, check the pins are exactly its vertices.
  halfedge_descriptor bhd;
  std::size_t borders = 0;
  for (halfedge_descriptor h : mesh.halfedges())
    if (mesh.is_border(h)) {
      if (bhd == Mesh::null_halfedge()) bhd = h;
      ++borders;
    }
  if (bhd == Mesh::null_halfedge()) return fail("the mesh has no border");
  std::size_t around = 0;
  for (halfedge_descriptor h : CGAL::halfedges_around_face(bhd, mesh)) {
    (void)h;
    ++around;
  }
  if (around != borders) return fail("the mesh has more than one border: not a disk");
  if (around != np) return fail("the pins are not exactly the border's vertices");

  // Unwritten positions stay NaN, so a vertex the solve never reached cannot pass for a result.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto uv = mesh.add_property_map<vertex_descriptor, Point_2>("v:uv", Point_2(nan, nan)).first;
  Given_border border{&pins, &pinned};
  const SMP::Error_code status = solver == "lu" ? run<Direct>(mesh, border, bhd, uv)
                                                : run<Iterative>(mesh, border, bhd, uv);
  if (status != SMP::OK)
    return fail(std::string("CGAL: ") + SMP::get_error_message(status) +
                " (a border vertex without a pin gives 'border too short')");

  for (vertex_descriptor v : mesh.vertices()) std::printf("%.17g %.17g\n", uv[v].x(), uv[v].y());
  return 0;
}
