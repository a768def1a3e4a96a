#pragma once
/// @file hom.hpp
/// Everything header-only in hom (needs only Eigen and Boost.Math).

#include "hom/element/family.hpp"
#include "hom/element/node_layout.hpp"
#include "hom/element/sub_elements.hpp"
