// Ray/triangle intersection: the watertight production test and the reference methods it is
// measured against (two plane-then-barycentric tests, Cramer's rule, Moller-Trumbore). Their
// formulas and sources are in docs/design.md §6, the watertight test's reasoning in §4.3.
//
// Conventions shared by every method, so that they are interchangeable:
// - A hit has a finite t in [ray.tmin, tmax] (inclusive) and barycentrics u, v: the weights of b
//   and c, so the hit point is (1 - u - v) a + u b + v c. A t that overflows is no hit.
// - Edges and vertices: the reference methods count a point on an edge or vertex as inside (>= 0
//   tests), so a ray through a shared edge hits both triangles, or, after rounding, neither. The
//   watertight method gives each shared edge and vertex to exactly one of the triangles around it.
// - The front face is the side that (b - a) x (c - a) points to. With cull_backfaces, a ray whose
//   direction has a positive dot product with that normal (it sees the back) does not hit.
// - No absolute epsilons. A ray parallel to the plane (denominator exactly 0) misses.
// - Every accept test is written as "if (!(inside)) reject", so a NaN anywhere rejects: NaN input
//   never produces a hit.
// - Degenerate triangles (cross product exactly zero: repeated or collinear vertices) never hit.
//   The free functions test for them; PreparedRay::intersect assumes the caller has filtered them
//   out (the BVH does so once at build time).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/ray.h"

// Triangle tests, box tests and the edge functions sit in the innermost loops of the BVH walks;
// GCC and Clang would otherwise keep the larger ones out of line there (a 3D traced beam called
// WideSlabRay::enter for every node).
// LASER_RAYCAST_HOT_LAMBDA: the same for a lambda, after its parameter list.
#if defined(__GNUC__)
#define LASER_RAYCAST_HOT_INLINE __attribute__((always_inline)) inline
#define LASER_RAYCAST_HOT_LAMBDA __attribute__((always_inline))
#else
#define LASER_RAYCAST_HOT_INLINE inline
#define LASER_RAYCAST_HOT_LAMBDA
#endif

namespace laser_raycast {
namespace core {

template <typename T>
struct TriangleHitT {
  T t;
  T u;  // weight of b
  T v;  // weight of c
};

enum class TriangleMethod { kSeedPlane, kSeedUv, kCramer, kMollerTrumbore, kWatertight };

inline constexpr std::array<TriangleMethod, 5> kAllTriangleMethods = {
    TriangleMethod::kSeedPlane, TriangleMethod::kSeedUv, TriangleMethod::kCramer,
    TriangleMethod::kMollerTrumbore, TriangleMethod::kWatertight};

// The names parameters, the CLI and the benchmark use.
inline const EnumNames<TriangleMethod, 5> kTriangleMethodNames{{{
    {TriangleMethod::kSeedPlane, "seed_plane"},
    {TriangleMethod::kSeedUv, "seed_uv"},
    {TriangleMethod::kCramer, "cramer"},
    {TriangleMethod::kMollerTrumbore, "moller_trumbore"},
    {TriangleMethod::kWatertight, "watertight"},
}}};
inline const char* toString(TriangleMethod method) { return kTriangleMethodNames.name(method); }
// Parses a name produced by toString(); false for anything else.
inline bool parseTriangleMethod(const std::string& name, TriangleMethod* method) {
  return kTriangleMethodNames.parse(name, method);
}

template <typename T>
inline bool isDegenerateTriangle(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  const Vec3<T> n = (b - a).cross(c - a);
  return n.x() == 0 && n.y() == 0 && n.z() == 0;
}

namespace detail {

// a * b - c * d with the sign of the exact result (and 0 only when the exact result is 0).
// For float the products are exact in double (a result too small for a float is returned as the
// smallest float of its sign). For double, Kahan's algorithm with FMA has a relative
// error of at most 2 ulp (Jeannerod, Louvet, Muller 2013), which preserves the sign. Slow for
// double without hardware FMA: edgeFunction() calls it only where rounding could have changed the
// sign.
inline float exactSignDifferenceOfProducts(float a, float b, float c, float d) {
  const double exact = double(a) * double(b) - double(c) * double(d);
  const float result = static_cast<float>(exact);
  // Too small for a float (it underflowed to 0): the smallest float of its sign.
  if (result == 0 && exact != 0) {
    return static_cast<float>(std::copysign(std::numeric_limits<float>::denorm_min(), exact));
  }
  return result;
}
inline double kahanDifferenceOfProducts(double a, double b, double c, double d) {
  const double cd = c * d;
  const double cd_error = std::fma(-c, d, cd);  // cd - c * d, exactly
  const double ab_minus_cd = std::fma(a, b, -cd);
  return ab_minus_cd + cd_error;
}
// Kahan's bound holds only while the products and their errors are normal numbers. Where they
// could underflow (found by test/fuzz/fuzz_core: coordinates 1e-160 apart turned an edge function
// of -1.9e-460 into -0, and a ray outside a triangle hit it) or overflow, a and c are scaled by one
// power of two and b and d by another: ab - cd scales by their product, so its sign is kept, and
// the scaling is the same with the pairs swapped, so neighbours still get opposite signs. A result
// too small for a double then comes back as the smallest one of its sign.
inline double exactSignDifferenceOfProducts(double a, double b, double c, double d) {
  const double ac = std::max(std::abs(a), std::abs(c)), bd = std::max(std::abs(b), std::abs(d));
  if (!(ac > 0 && bd > 0 && ac <= std::numeric_limits<double>::max() &&
        bd <= std::numeric_limits<double>::max())) {
    return kahanDifferenceOfProducts(a, b, c, d);  // a zero or non-finite factor: nothing to save
  }
  // Both factors within 2^+-449 (the usual case, tested without ilogb, which is a libm call):
  // their exponents sum to within +-898.
  constexpr double kLow = 0x1p-449, kHigh = 0x1p449;
  if (ac > kLow && ac < kHigh && bd > kLow && bd < kHigh) {
    return kahanDifferenceOfProducts(a, b, c, d);
  }
  const int i = std::ilogb(ac), j = std::ilogb(bd);
  if (i + j > -900 && i + j < 900) return kahanDifferenceOfProducts(a, b, c, d);
  const double scaled = kahanDifferenceOfProducts(std::ldexp(a, -i), std::ldexp(b, -j),
                                                  std::ldexp(c, -i), std::ldexp(d, -j));
  const double result = std::ldexp(scaled, i + j);
  if (result == 0 && scaled != 0) {
    return std::copysign(std::numeric_limits<double>::denorm_min(), scaled);
  }
  return result;
}

// An edge function a * b - c * d with its exact sign. The rounded difference is kept where rounding
// cannot have changed its sign (the products' rounding errors total at most u (|ab| + |cd|), and
// the subtraction's own rounding keeps the sign); otherwise it is recomputed. The two triangles
// sharing an edge evaluate it with the pairs swapped: the same rounded products, so the same branch
// and exactly opposite signs, and 0 for both only when the ray meets the edge exactly. An
// evaluation that used the exact sign in one triangle and the rounded one in its neighbour could
// let a ray slip between.
template <typename T>
LASER_RAYCAST_HOT_INLINE T edgeFunction(T a, T b, T c, T d) {
  const T ab = a * b;
  const T cd = c * d;
  const T e = ab - cd;
  // A product in the subnormal range is off by up to half the smallest subnormal, not by a relative
  // amount: that much more must separate e from 0.
  if (std::abs(e) > std::numeric_limits<T>::epsilon() * (std::abs(ab) + std::abs(cd)) +
                        std::numeric_limits<T>::denorm_min()) {
    return e;
  }
  return exactSignDifferenceOfProducts(a, b, c, d);
}

// Whether a triangle owns a boundary point on its edge with direction (dx, dy) (the edge as
// traversed by a triangle that faces the ray, reversed for one that does not; the ray at the origin
// of the projection). It does iff the ray, nudged by a fixed infinitesimal offset, passes inside:
// the same rule for every triangle, so exactly one of two neighbours owns their shared edge, and
// one triangle of a fan its shared vertex (rasterisation's top-left rule is this idea).
template <typename T>
inline bool ownsBoundary(T dx, T dy) {
  return dy > 0 || (dy == 0 && dx > 0);
}

// Whether a computed t is a hit: in [tmin, tmax] (inclusive) and finite. A t that overflowed to
// +-Inf (a far triangle along a short direction: the true t exceeds the largest finite value) is
// no hit, even when tmax is +Inf, the Ray default. Written so that NaN fails.
template <typename T>
inline bool acceptsT(T t, T tmin, T tmax) {
  return t >= tmin && t <= tmax && std::abs(t) <= std::numeric_limits<T>::max();
}

// The end of the watertight test where det = ea + eb + ec, 1 / det or the scaled t leave the finite
// range: edge functions near the largest double (a vertex ~1e308 from the ray; found by
// test/fuzz/fuzz_core: det overflowed to +Inf, t = scaled_t / Inf came out -0 and a ray whose
// true hit lay at t = -0.19 hit at its origin) or so small that 1 / det is infinite (a triangle
// ~1e-154 m across in double, or a small one seen nearly edge-on). t, u and v are ratios of the
// edge functions, so scaling all three by one power of two (exact, but for digits far below the
// largest one's) changes none of them and brings det into [1, 6). An edge function that is itself
// infinite or NaN leaves nothing to recover: no hit.
template <typename T>
std::optional<TriangleHitT<T>> rescaledHit(T ea, T eb, T ec, T az, T bz, T cz, T tmin, T tmax) {
  const T largest = std::max({std::abs(ea), std::abs(eb), std::abs(ec)});
  if (!(largest > 0 && largest <= std::numeric_limits<T>::max())) return std::nullopt;
  const int exponent = std::ilogb(largest);
  ea = std::ldexp(ea, -exponent);
  eb = std::ldexp(eb, -exponent);
  ec = std::ldexp(ec, -exponent);
  const T det = ea + eb + ec;  // the three share a sign, so |det| >= 1
  const T t = (ea * az + eb * bz + ec * cz) / det;
  if (!acceptsT(t, tmin, tmax)) return std::nullopt;
  return TriangleHitT<T>{t, eb / det, ec / det};
}

}  // namespace detail

// A ray prepared for testing many triangles with one method. intersect() takes the current far
// limit so that closest-hit traversal can shrink it; it assumes a non-degenerate triangle.
template <typename T, TriangleMethod M>
class PreparedRay;

// docs/design.md §6.1: the plane H = [N, -N.A] with N = (B - A) x (C - B), t = -H.[V,1] / H.[W,0],
// then the barycentrics from the in-plane perpendiculars pA = N x (C - B), pB = N x (A - C),
// pC = N x (B - A). Kept as its source writes it (with the complete algorithm's pB; the source's
// prose once prints N x (A - B)).
template <typename T>
class PreparedRay<T, TriangleMethod::kSeedPlane> {
 public:
  PreparedRay(const RayT<T>& ray, bool cull_backfaces) : ray_(ray), cull_(cull_backfaces) {}

  LASER_RAYCAST_HOT_INLINE std::optional<TriangleHitT<T>> intersect(const Vec3<T>& a,
                                                                    const Vec3<T>& b,
                                                                    const Vec3<T>& c,
                                                                    T tmax) const {
    const Vec3<T> n = (b - a).cross(c - b);
    const T h_w = -n.dot(a);
    const T denom = n.dot(ray_.dir);  // H.[W,0]
    if (!(denom != 0)) return std::nullopt;
    if (cull_ && denom > 0) return std::nullopt;
    const T t = -(n.dot(ray_.origin) + h_w) / denom;  // -H.[V,1] / H.[W,0]
    if (!detail::acceptsT(t, ray_.tmin, tmax)) return std::nullopt;
    const Vec3<T> p = ray_.origin + t * ray_.dir;
    const Vec3<T> pa = n.cross(c - b);
    const Vec3<T> pb = n.cross(a - c);
    const Vec3<T> pc = n.cross(b - a);
    const T wa = (p - b).dot(pa) / (a - b).dot(pa);
    const T wb = (p - c).dot(pb) / (b - c).dot(pb);
    const T wc = (p - a).dot(pc) / (c - a).dot(pc);
    // A hit's barycentrics are finite: an overflowing one (a denominator near the smallest
    // number; found by test/fuzz/fuzz_core) is no hit. All three >= 0: their sum is finite iff each
    // is.
    if (!(wa >= 0 && wb >= 0 && wc >= 0) || !std::isfinite(wa + wb + wc)) return std::nullopt;
    return TriangleHitT<T>{t, wb, wc};
  }

 private:
  RayT<T> ray_;
  bool cull_;
};

// docs/design.md §6.2: unit normal n = AC x AB, S = R + r (n.RA / n.r), then u, v from the dot
// products of AB, AC, AS.
template <typename T>
class PreparedRay<T, TriangleMethod::kSeedUv> {
 public:
  PreparedRay(const RayT<T>& ray, bool cull_backfaces) : ray_(ray), cull_(cull_backfaces) {}

  LASER_RAYCAST_HOT_INLINE std::optional<TriangleHitT<T>> intersect(const Vec3<T>& a,
                                                                    const Vec3<T>& b,
                                                                    const Vec3<T>& c,
                                                                    T tmax) const {
    const Vec3<T> ab = b - a;
    const Vec3<T> ac = c - a;
    Vec3<T> n = ac.cross(ab);
    const T length = n.norm();
    if (!(length > 0)) return std::nullopt;
    n /= length;
    const T n_dot_r = n.dot(ray_.dir);
    if (!(n_dot_r != 0)) return std::nullopt;
    // This normal is AC x AB, the opposite of our front normal, so a back face has n.r < 0.
    if (cull_ && n_dot_r < 0) return std::nullopt;
    const T t = n.dot(a - ray_.origin) / n_dot_r;
    if (!detail::acceptsT(t, ray_.tmin, tmax)) return std::nullopt;
    const Vec3<T> as = ray_.origin + t * ray_.dir - a;
    const T ab_as = ab.dot(as);
    const T ac_ac = ac.dot(ac);
    const T ab_ac = ab.dot(ac);
    const T ac_as = ac.dot(as);
    const T ab_ab = ab.dot(ab);
    const T denom = ab_ab * ac_ac - ab_ac * ab_ac;
    const T u = (ab_as * ac_ac - ab_ac * ac_as) / denom;
    // The source prints this numerator with the opposite sign, (AB.AS)(AB.AC) - (AB.AB)(AC.AS);
    // solving AS = u AB + v AC by Cramer's rule gives the form below, the only one that passes the
    // tests.
    const T v = (ab_ab * ac_as - ab_ac * ab_as) / denom;
    if (!(u >= 0 && v >= 0 && u + v <= 1)) return std::nullopt;
    return TriangleHitT<T>{t, u, v};
  }

 private:
  RayT<T> ray_;
  bool cull_;
};

// docs/design.md §6.3: [a - b, a - c, d] [beta, gamma, t]^T = a - p by Cramer's rule,
// det[x y z] = x . (y x z).
template <typename T>
class PreparedRay<T, TriangleMethod::kCramer> {
 public:
  PreparedRay(const RayT<T>& ray, bool cull_backfaces) : ray_(ray), cull_(cull_backfaces) {}

  LASER_RAYCAST_HOT_INLINE std::optional<TriangleHitT<T>> intersect(const Vec3<T>& a,
                                                                    const Vec3<T>& b,
                                                                    const Vec3<T>& c,
                                                                    T tmax) const {
    const Vec3<T> e1 = a - b;
    const Vec3<T> e2 = a - c;
    const Vec3<T> r = a - ray_.origin;
    const Vec3<T> e2_x_d = e2.cross(ray_.dir);
    const T m = e1.dot(e2_x_d);  // det[e1 e2 d] = d . ((b - a) x (c - a))
    if (!(m != 0)) return std::nullopt;
    if (cull_ && m > 0) return std::nullopt;
    const T beta = r.dot(e2_x_d) / m;  // det[r e2 d]
    const Vec3<T> e1_x_r = e1.cross(r);
    const T gamma = ray_.dir.dot(e1_x_r) / m;  // det[e1 r d]
    const T t = -e2.dot(e1_x_r) / m;           // det[e1 e2 r]
    if (!(beta >= 0 && gamma >= 0 && beta + gamma <= 1)) return std::nullopt;
    if (!detail::acceptsT(t, ray_.tmin, tmax)) return std::nullopt;
    return TriangleHitT<T>{t, beta, gamma};
  }

 private:
  RayT<T> ray_;
  bool cull_;
};

// Moller & Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection" (1997), without its epsilon.
template <typename T>
class PreparedRay<T, TriangleMethod::kMollerTrumbore> {
 public:
  PreparedRay(const RayT<T>& ray, bool cull_backfaces) : ray_(ray), cull_(cull_backfaces) {}

  LASER_RAYCAST_HOT_INLINE std::optional<TriangleHitT<T>> intersect(const Vec3<T>& a,
                                                                    const Vec3<T>& b,
                                                                    const Vec3<T>& c,
                                                                    T tmax) const {
    const Vec3<T> e1 = b - a;
    const Vec3<T> e2 = c - a;
    const Vec3<T> p = ray_.dir.cross(e2);
    const T det = e1.dot(p);  // = -d . ((b - a) x (c - a)): positive for a front face
    if (cull_ ? !(det > 0) : !(det != 0)) return std::nullopt;
    const T inv_det = T(1) / det;
    const Vec3<T> s = ray_.origin - a;
    const T u = s.dot(p) * inv_det;
    if (!(u >= 0 && u <= 1)) return std::nullopt;
    const Vec3<T> q = s.cross(e1);
    const T v = ray_.dir.dot(q) * inv_det;
    if (!(v >= 0 && u + v <= 1)) return std::nullopt;
    const T t = e2.dot(q) * inv_det;
    if (!detail::acceptsT(t, ray_.tmin, tmax)) return std::nullopt;
    return TriangleHitT<T>{t, u, v};
  }

 private:
  RayT<T> ray_;
  bool cull_;
};

// Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013. The vertices are
// moved into a frame where the ray starts at the origin and runs along +z, and the hit is decided
// by the signs of three 2D edge functions. Neighbouring triangles evaluate a shared edge from the
// same transformed vertices, with its sign computed exactly (detail::edgeFunction; pbrt-v4
// recomputes in double only where a float edge function is exactly 0), so a ray never slips between
// them; and a ray exactly on a shared edge or vertex that it crosses hits exactly one of the
// triangles around it (detail::ownsBoundary; on a silhouette, where the surface only touches the
// ray, none or two).
template <typename T>
class PreparedRay<T, TriangleMethod::kWatertight> {
 public:
  PreparedRay(const RayT<T>& ray, bool cull_backfaces)
      // An invalid ray gets tmin = NaN, so that no t passes the range test. An infinite direction
      // component would otherwise give sz_ = 0 and a hit at t = 0 on every triangle the ray's line
      // crosses.
      : PreparedRay(ray, cull_backfaces,
                    isValidRay(ray) ? ray.tmin : std::numeric_limits<T>::quiet_NaN()) {}
  // A ray its maker knows to be valid (isValidRay), not checked again: a sweep's beam, a finite
  // pose's turn of a unit direction (BeamRays, for every triangle a beam is tested against).
  struct KnownValid {};
  PreparedRay(const RayT<T>& ray, bool cull_backfaces, KnownValid)
      : PreparedRay(ray, cull_backfaces, ray.tmin) {}

  // All that a prepared ray keeps of its direction: the permutation that makes z the direction's
  // largest component and the shear that maps the direction to (0, 0, 1). Made once for a
  // direction cast again and again (a divergent beam's sub-ray, scan after scan: BeamSet).
  struct Shear {
    T sx, sy, sz;
    std::int8_t kx, ky, kz;
  };
  LASER_RAYCAST_HOT_INLINE static Shear shearOf(const Vec3<T>& dir) {
    // Swapping x and y when the largest component is negative keeps the winding (and so the front
    // face) unchanged.
    int kz = 0;
    if (std::abs(dir.y()) > std::abs(dir[kz])) kz = 1;
    if (std::abs(dir.z()) > std::abs(dir[kz])) kz = 2;
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (dir[kz] < 0) std::swap(kx, ky);
    return Shear{dir[kx] / dir[kz], dir[ky] / dir[kz], T(1) / dir[kz], static_cast<std::int8_t>(kx),
                 static_cast<std::int8_t>(ky), static_cast<std::int8_t>(kz)};
  }
  // The valid ray from origin along the direction shear was made of (shearOf), from tmin: the same
  // as the ray prepared from it.
  PreparedRay(const Vec3<T>& origin, T tmin, bool cull_backfaces, const Shear& shear)
      : origin_(origin),
        tmin_(tmin),
        cull_(cull_backfaces),
        kx_(shear.kx),
        ky_(shear.ky),
        kz_(shear.kz),
        sx_(shear.sx),
        sy_(shear.sy),
        sz_(shear.sz) {}

 private:
  PreparedRay(const RayT<T>& ray, bool cull_backfaces, T tmin)
      : PreparedRay(ray.origin, tmin, cull_backfaces, shearOf(ray.dir)) {}

 public:
  LASER_RAYCAST_HOT_INLINE std::optional<TriangleHitT<T>> intersect(const Vec3<T>& a,
                                                                    const Vec3<T>& b,
                                                                    const Vec3<T>& c,
                                                                    T tmax) const {
    // Translate to the ray origin, then shear x and y (z is scaled only once the hit is known).
    const Vec3<T> pa = a - origin_;
    const Vec3<T> pb = b - origin_;
    const Vec3<T> pc = c - origin_;
    const T ax = pa[kx_] - sx_ * pa[kz_];
    const T ay = pa[ky_] - sy_ * pa[kz_];
    const T bx = pb[kx_] - sx_ * pb[kz_];
    const T by = pb[ky_] - sy_ * pb[kz_];
    const T cx = pc[kx_] - sx_ * pc[kz_];
    const T cy = pc[ky_] - sy_ * pc[kz_];

    // Edge functions, with exact signs: twice the signed areas of the sub-triangles opposite a, b
    // and c, seen along the ray.
    const T ea = detail::edgeFunction(cx, by, cy, bx);
    const T eb = detail::edgeFunction(ax, cy, ay, cx);
    const T ec = detail::edgeFunction(bx, ay, by, ax);
    // Inside iff all three have one sign; zeros (the ray exactly on an edge) are settled below.
    if ((ea < 0 || eb < 0 || ec < 0) && (ea > 0 || eb > 0 || ec > 0)) return std::nullopt;
    const T det = ea + eb + ec;            // positive for a front face
    if (!(det != 0)) return std::nullopt;  // ray in the triangle's plane, or NaN
    if (cull_ && det < 0) return std::nullopt;
    if (ea == 0 || eb == 0 || ec == 0) {
      // On an edge or a vertex: hit only if this triangle owns it. The edges are oriented as a
      // front-facing triangle traverses them, so the rule does not depend on the winding.
      const T s = det > 0 ? T(1) : T(-1);
      if (ea == 0 && !detail::ownsBoundary(s * (cx - bx), s * (cy - by))) return std::nullopt;
      if (eb == 0 && !detail::ownsBoundary(s * (ax - cx), s * (ay - cy))) return std::nullopt;
      if (ec == 0 && !detail::ownsBoundary(s * (bx - ax), s * (by - ay))) return std::nullopt;
    }

    // Scaled hit distance, then t.
    const T az = sz_ * pa[kz_];
    const T bz = sz_ * pb[kz_];
    const T cz = sz_ * pc[kz_];
    const T scaled_t = ea * az + eb * bz + ec * cz;
    const T inv_det = T(1) / det;
    constexpr T kMax = std::numeric_limits<T>::max();
    if (!(std::abs(det) <= kMax && std::abs(inv_det) <= kMax && std::abs(scaled_t) <= kMax)) {
      return detail::rescaledHit(ea, eb, ec, az, bz, cz, tmin_, tmax);
    }
    const T t = scaled_t * inv_det;
    if (!detail::acceptsT(t, tmin_, tmax)) return std::nullopt;
    return TriangleHitT<T>{t, eb * inv_det, ec * inv_det};
  }

 private:
  Vec3<T> origin_;
  T tmin_;
  bool cull_;
  int kx_, ky_, kz_;
  T sx_, sy_, sz_;
};

// Calls f(std::integral_constant<TriangleMethod, m>{}) for the runtime method m, so that hot loops
// are compiled once per method.
template <typename F>
decltype(auto) dispatchTriangleMethod(TriangleMethod method, F&& f) {
  switch (method) {
    case TriangleMethod::kSeedPlane:
      return f(std::integral_constant<TriangleMethod, TriangleMethod::kSeedPlane>{});
    case TriangleMethod::kSeedUv:
      return f(std::integral_constant<TriangleMethod, TriangleMethod::kSeedUv>{});
    case TriangleMethod::kCramer:
      return f(std::integral_constant<TriangleMethod, TriangleMethod::kCramer>{});
    case TriangleMethod::kMollerTrumbore:
      return f(std::integral_constant<TriangleMethod, TriangleMethod::kMollerTrumbore>{});
    case TriangleMethod::kWatertight:
    default:
      return f(std::integral_constant<TriangleMethod, TriangleMethod::kWatertight>{});
  }
}

// The single-triangle entry points, one free function per method (the method as a template
// argument) and the same selected at run time. Both reject degenerate triangles, then run the
// method.
template <TriangleMethod M, typename T>
std::optional<TriangleHitT<T>> intersectTriangle(const RayT<T>& ray, const Vec3<T>& a,
                                                 const Vec3<T>& b, const Vec3<T>& c,
                                                 bool cull_backfaces = false) {
  if (isDegenerateTriangle(a, b, c)) return std::nullopt;
  return PreparedRay<T, M>(ray, cull_backfaces).intersect(a, b, c, ray.tmax);
}

template <typename T>
std::optional<TriangleHitT<T>> intersectTriangle(TriangleMethod method, const RayT<T>& ray,
                                                 const Vec3<T>& a, const Vec3<T>& b,
                                                 const Vec3<T>& c, bool cull_backfaces = false) {
  return dispatchTriangleMethod(method, [&](auto m) {
    return intersectTriangle<decltype(m)::value>(ray, a, b, c, cull_backfaces);
  });
}

}  // namespace core
}  // namespace laser_raycast
