// The names benchmarks and test reports print for glint's ray-triangle tests (the library's
// types carry none). A policy without a name here prints "intersector".
#pragma once

#include <glint/intersection/ivm.hpp>
#include <glint/intersection/moller_trumbore.hpp>
#include <glint/intersection/wald.hpp>
#include <glint/intersection/watertight.hpp>

namespace glint::bench {

template <class P>
inline constexpr const char* intersector_name = "intersector";
template <class T>
inline constexpr const char* intersector_name<Ivm<T>> = "Ivm";
template <class T>
inline constexpr const char* intersector_name<MollerTrumbore<T>> = "MollerTrumbore";
template <class T>
inline constexpr const char* intersector_name<Wald<T>> = "Wald";
template <class T>
inline constexpr const char* intersector_name<Watertight<T>> = "Watertight";

}  // namespace glint::bench
