// A minimal program using hom's header-only core: it prints the number of
// nodes and linear sub-elements of a degree-4 tetrahedron.
#include <iostream>

#include <hom/hom.hpp>

int main() {
  using Tet = hom::Simplex<3>;
  const int p = 4;
  std::cout << "tetrahedron p=" << p << " nodes=" << Tet::num_nodes(p)
            << " sub-elements=" << hom::linear_sub_elements<Tet>(p).size() << "\n";
  return hom::linear_sub_elements<Tet>(p).size() == 64 ? 0 : 1;
}
