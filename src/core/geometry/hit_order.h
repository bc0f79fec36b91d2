// The order of two hits of one beam: the nearer first, and at the same distance the lower body, then
// the lower triangle index. Every walk keeps a beam's hit by this one rule, so a beam's result never
// depends on the order in which bodies, nodes, triangles or beams are visited (nor, so, on how the
// beams are split between threads).
#pragma once

namespace laser_raycast {
namespace core {

// The arguments are references so that, inlined, a hit's body and triangle are read only when the
// distances tie (the common case compares two distances and nothing else).

// Whether (body, triangle) goes before (other_body, other_triangle) at the same distance.
template <class Index>
inline bool tieBefore(const int& body, const Index& triangle, const int& other_body,
                      const Index& other_triangle) {
  return body < other_body || (body == other_body && triangle < other_triangle);
}

// Whether the hit (t, body, triangle) goes before the hit (other_t, other_body, other_triangle).
template <class Index>
inline bool hitBefore(double t, const int& body, const Index& triangle, double other_t,
                      const int& other_body, const Index& other_triangle) {
  return t < other_t ||
         (t == other_t && tieBefore(body, triangle, other_body, other_triangle));
}

// The same within one body: the nearer, or as near on a lower triangle index.
template <class Index>
inline bool hitBefore(double t, const Index& triangle, double other_t,
                      const Index& other_triangle) {
  return t < other_t || (t == other_t && triangle < other_triangle);
}

}  // namespace core
}  // namespace laser_raycast
