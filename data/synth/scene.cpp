// Ray queries (quad, oriented box, sphere, cylinder) over a small BVH, procedural materials and shading.
#include "data/synth/scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace isplat::synth {

constexpr double kEps = 1e-7;

// ---------------------------------------------------------------- noise
double hash01(int64_t x, int64_t y, int64_t z, uint64_t salt) {
  uint64_t h = salt * 0x9E3779B97F4A7C15ull;
  for (int64_t v : {x, y, z}) {
    h ^= static_cast<uint64_t>(v) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
  }
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

double value_noise(const Vec3& p, uint64_t salt) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy), iz = static_cast<int64_t>(fz);
  auto smooth = [](double t) { return t * t * (3.0 - 2.0 * t); };
  const double tx = smooth(p.x() - fx), ty = smooth(p.y() - fy), tz = smooth(p.z() - fz);
  double acc = 0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const double w = (dx ? tx : 1 - tx) * (dy ? ty : 1 - ty) * (dz ? tz : 1 - tz);
        acc += w * hash01(ix + dx, iy + dy, iz + dz, salt);
      }
  return acc;
}

double fbm(const Vec3& p, int octaves, uint64_t salt) {
  double sum = 0, amp = 0.5, norm = 0;
  Vec3 q = p;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * value_noise(q, salt + o);
    norm += amp;
    amp *= 0.5;
    q *= 2.03;
  }
  return sum / norm;
}

// ---------------------------------------------------------------- materials
Vec3 Material::albedo(double s, double t, const Vec3& p) const {
  const double x = s / scale, y = t / scale;
  auto mix = [&](double w) { return (a * (1.0 - w) + b * w).eval(); };
  switch (pattern) {
    case Pattern::Solid:
      return mix(0.15 * fbm(p * 4.0 / scale, 3, 11));
    case Pattern::Checker: {
      const int c = (static_cast<int>(std::floor(x)) + static_cast<int>(std::floor(y))) & 1;
      return mix(c ? 0.9 : 0.1 + 0.1 * fbm(p * 8.0, 2, 3));
    }
    case Pattern::Stripes: {
      const double v = 0.5 + 0.5 * std::sin(2 * kPi * x + 2.0 * fbm(p * 3.0, 2, 5));
      return mix(v > 0.5 ? 0.85 : 0.15);
    }
    case Pattern::Noise:
      return mix(fbm(Vec3(x, y, p.z() / scale) * 4.0, 5, 7));
    case Pattern::Bricks: {
      const double row = std::floor(y * 3.0);
      const double xx = x * 1.5 + 0.5 * (static_cast<int64_t>(row) & 1);
      const double fx = xx - std::floor(xx), fy = y * 3.0 - row;
      const bool mortar = fx < 0.06 || fy < 0.1;
      const double tone = 0.25 * hash01(static_cast<int64_t>(std::floor(xx)), static_cast<int64_t>(row), 0, 17);
      return mortar ? Vec3(0.75, 0.74, 0.7) : mix(tone + 0.2 * fbm(p * 20.0, 2, 9));
    }
    case Pattern::Wood: {
      const double r = std::sqrt(x * x * 0.02 + y * y) * 6.0 + 3.0 * fbm(Vec3(x, y, 0) * 2.0, 3, 13);
      return mix(0.5 + 0.5 * std::sin(r * 2 * kPi));
    }
    case Pattern::Tiles: {
      const double fx = x - std::floor(x), fy = y - std::floor(y);
      const bool grout = fx < 0.04 || fy < 0.04;
      const double tone = hash01(static_cast<int64_t>(std::floor(x)), static_cast<int64_t>(std::floor(y)), 1, 23);
      return grout ? Vec3(0.2, 0.2, 0.2) : mix(0.3 * tone + 0.4 * fbm(p * 6.0, 3, 29));
    }
    case Pattern::Marble: {
      const double v = std::sin((x + 4.0 * fbm(Vec3(x, y, p.z()) * 1.5, 5, 31)) * kPi);
      return mix(std::pow(std::fabs(v), 0.4));
    }
    case Pattern::Dots: {
      const double fx = x - std::floor(x) - 0.5, fy = y - std::floor(y) - 0.5;
      return mix(fx * fx + fy * fy < 0.09 ? 1.0 : 0.0);
    }
    case Pattern::Grid: {
      const double fx = x - std::floor(x), fy = y - std::floor(y);
      return mix((fx < 0.08 || fy < 0.08) ? 1.0 : 0.2 * fbm(p * 5.0, 2, 37));
    }
  }
  return a;
}

// ---------------------------------------------------------------- primitives
void Primitive::finalize() {
  switch (shape) {
    case Shape::Quad: {
      bmin = p0.cwiseMin(p0 + e1).cwiseMin(p0 + e2).cwiseMin(p0 + e1 + e2);
      bmax = p0.cwiseMax(p0 + e1).cwiseMax(p0 + e2).cwiseMax(p0 + e1 + e2);
      break;
    }
    case Shape::Box: {
      const Vec3 ext = R.cwiseAbs() * half;
      bmin = p0 - ext;
      bmax = p0 + ext;
      break;
    }
    case Shape::Sphere:
      bmin = p0 - Vec3::Constant(radius);
      bmax = p0 + Vec3::Constant(radius);
      break;
    case Shape::Cylinder: {
      const Vec3 top = p0 + R.col(2) * height;
      const Vec3 ext = (R.col(0).cwiseAbs() + R.col(1).cwiseAbs()) * radius;
      bmin = p0.cwiseMin(top) - ext;
      bmax = p0.cwiseMax(top) + ext;
      break;
    }
  }
  bmin -= Vec3::Constant(1e-6);
  bmax += Vec3::Constant(1e-6);
}

namespace {

bool slab(const Vec3& o, const Vec3& inv, const Vec3& bmin, const Vec3& bmax, double tmax, double& t0) {
  double lo = 0.0, hi = tmax;
  for (int k = 0; k < 3; ++k) {
    double a = (bmin[k] - o[k]) * inv[k], b = (bmax[k] - o[k]) * inv[k];
    if (a > b) std::swap(a, b);
    lo = std::max(lo, a);
    hi = std::min(hi, b);
    if (lo > hi) return false;
  }
  t0 = lo;
  return true;
}

bool hit_quad(const Primitive& q, const Vec3& o, const Vec3& d, double tmax, Hit& h) {
  const Vec3 N = q.e1.cross(q.e2);
  const double denom = N.dot(d);
  if (std::fabs(denom) < 1e-12) return false;
  const double t = N.dot(q.p0 - o) / denom;
  if (t < kEps || t >= tmax) return false;
  const Vec3 rel = o + t * d - q.p0;
  const Vec3 w = N / N.squaredNorm();
  const double a = w.dot(rel.cross(q.e2)), b = w.dot(q.e1.cross(rel));
  if (a < 0 || a > 1 || b < 0 || b > 1) return false;
  h.t = t;
  h.n = N.normalized();
  h.s = a * q.e1.norm();
  h.u = b * q.e2.norm();
  return true;
}

bool hit_box(const Primitive& b, const Vec3& o, const Vec3& d, double tmax, Hit& h) {
  const Vec3 ol = b.R.transpose() * (o - b.p0), dl = b.R.transpose() * d;
  double lo = -1e300, hi = 1e300;
  int axis_lo = 0, axis_hi = 0;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(dl[k]) < 1e-15) {
      if (ol[k] < -b.half[k] || ol[k] > b.half[k]) return false;
      continue;
    }
    double t1 = (-b.half[k] - ol[k]) / dl[k], t2 = (b.half[k] - ol[k]) / dl[k];
    if (t1 > t2) std::swap(t1, t2);
    if (t1 > lo) lo = t1, axis_lo = k;
    if (t2 < hi) hi = t2, axis_hi = k;
    if (lo > hi) return false;
  }
  double t = lo;
  int axis = axis_lo;
  if (t < kEps) {  // origin inside the box: take the exit face
    t = hi;
    axis = axis_hi;
  }
  if (t < kEps || t >= tmax) return false;
  const Vec3 pl = ol + t * dl;
  Vec3 nl = Vec3::Zero();
  nl[axis] = pl[axis] > 0 ? 1.0 : -1.0;
  h.t = t;
  h.n = b.R * nl;
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  h.s = pl[i] + b.half[i];
  h.u = pl[j] + b.half[j];
  return true;
}

bool hit_sphere(const Primitive& s, const Vec3& o, const Vec3& d, double tmax, Hit& h) {
  const Vec3 oc = o - s.p0;
  const double bq = oc.dot(d), c = oc.squaredNorm() - s.radius * s.radius;
  const double disc = bq * bq - c;
  if (disc < 0) return false;
  const double sq = std::sqrt(disc);
  double t = -bq - sq;
  if (t < kEps) t = -bq + sq;
  if (t < kEps || t >= tmax) return false;
  const Vec3 n = (oc + t * d) / s.radius;
  h.t = t;
  h.n = n;
  h.s = std::atan2(n.y(), n.x()) * s.radius;
  h.u = std::acos(std::clamp(n.z(), -1.0, 1.0)) * s.radius;
  return true;
}

bool hit_cylinder(const Primitive& c, const Vec3& o, const Vec3& d, double tmax, Hit& h) {
  const Vec3 ol = c.R.transpose() * (o - c.p0), dl = c.R.transpose() * d;
  bool found = false;
  double best = tmax;
  Vec3 nl;
  double s = 0, u = 0;
  const double A = dl.x() * dl.x() + dl.y() * dl.y();
  if (A > 1e-15) {
    const double B = ol.x() * dl.x() + ol.y() * dl.y();
    const double C = ol.x() * ol.x() + ol.y() * ol.y() - c.radius * c.radius;
    const double disc = B * B - A * C;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      for (double t : {(-B - sq) / A, (-B + sq) / A}) {
        if (t < kEps || t >= best) continue;
        const Vec3 p = ol + t * dl;
        if (p.z() < 0 || p.z() > c.height) continue;
        best = t;
        found = true;
        nl = Vec3(p.x(), p.y(), 0) / c.radius;
        s = std::atan2(p.y(), p.x()) * c.radius;
        u = p.z();
        break;
      }
    }
  }
  if (std::fabs(dl.z()) > 1e-15) {
    for (double zc : {0.0, c.height}) {
      const double t = (zc - ol.z()) / dl.z();
      if (t < kEps || t >= best) continue;
      const Vec3 p = ol + t * dl;
      if (p.x() * p.x() + p.y() * p.y() > c.radius * c.radius) continue;
      best = t;
      found = true;
      nl = Vec3(0, 0, zc > 0 ? 1 : -1);
      s = p.x() + c.radius;
      u = p.y() + c.radius;
    }
  }
  if (!found) return false;
  h.t = best;
  h.n = c.R * nl;
  h.s = s;
  h.u = u;
  return true;
}

bool hit_primitive(const Primitive& p, const Vec3& o, const Vec3& d, double tmax, Hit& h) {
  switch (p.shape) {
    case Shape::Quad:
      return hit_quad(p, o, d, tmax, h);
    case Shape::Box:
      return hit_box(p, o, d, tmax, h);
    case Shape::Sphere:
      return hit_sphere(p, o, d, tmax, h);
    case Shape::Cylinder:
      return hit_cylinder(p, o, d, tmax, h);
  }
  return false;
}

}  // namespace

// ---------------------------------------------------------------- scene
int Scene::add_material(const Material& m) {
  materials.push_back(m);
  return static_cast<int>(materials.size()) - 1;
}

void Scene::add(Primitive p) {
  p.finalize();
  prims.push_back(p);
}

int Scene::build_node(int first, int count) {
  Node node;
  node.bmin = Vec3::Constant(1e300);
  node.bmax = Vec3::Constant(-1e300);
  for (int i = first; i < first + count; ++i) {
    node.bmin = node.bmin.cwiseMin(prims[order_[i]].bmin);
    node.bmax = node.bmax.cwiseMax(prims[order_[i]].bmax);
  }
  const int index = static_cast<int>(nodes_.size());
  nodes_.push_back(node);
  if (count <= 2) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  // Median split of primitive centres along the widest axis.
  int axis = 0;
  const Vec3 ext = node.bmax - node.bmin;
  if (ext.y() > ext[axis]) axis = 1;
  if (ext.z() > ext[axis]) axis = 2;
  const int mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count, [&](int a, int b) {
    return prims[a].bmin[axis] + prims[a].bmax[axis] < prims[b].bmin[axis] + prims[b].bmax[axis];
  });
  const int left = build_node(first, mid - first);
  const int right = build_node(mid, first + count - mid);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

void Scene::build() {
  nodes_.clear();
  order_.resize(prims.size());
  for (size_t i = 0; i < prims.size(); ++i) order_[i] = static_cast<int>(i);
  if (!prims.empty()) build_node(0, static_cast<int>(prims.size()));
}

template <bool AnyHit>
bool Scene::traverse(const Vec3& o, const Vec3& d, double tmax, Hit* hit) const {
  if (nodes_.empty()) return false;
  const Vec3 inv(1.0 / (std::fabs(d.x()) > 1e-15 ? d.x() : 1e-15), 1.0 / (std::fabs(d.y()) > 1e-15 ? d.y() : 1e-15),
                 1.0 / (std::fabs(d.z()) > 1e-15 ? d.z() : 1e-15));
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  bool found = false;
  double best = tmax;
  Hit h;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    double t0;
    if (!slab(o, inv, n.bmin, n.bmax, best, t0)) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const Primitive& p = prims[order_[i]];
        if (hit_primitive(p, o, d, best, h)) {
          if (AnyHit) return true;
          best = h.t;
          h.material = p.material;
          *hit = h;
          found = true;
        }
      }
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return found;
}

bool Scene::intersect(const Vec3& o, const Vec3& d, double tmax, Hit& hit) const {
  if (!traverse<false>(o, d, tmax, &hit)) return false;
  hit.p = o + hit.t * d;
  if (hit.n.dot(d) > 0) hit.n = -hit.n;  // double-sided surfaces
  return true;
}

bool Scene::occluded(const Vec3& o, const Vec3& d, double tmax) const {
  return traverse<true>(o, d, tmax, nullptr);
}

Vec3 Scene::sky(const Vec3& d) const {
  const double e = std::clamp(d.z(), -0.2, 1.0);
  Vec3 c = sky_horizon + (sky_zenith - sky_horizon) * std::sqrt(std::max(0.0, e));
  const double sun = std::max(0.0, d.dot(sun_dir));
  c += sun_radiance * 0.02 * std::pow(sun, 64.0);
  // Soft clouds keep the sky from being flat.
  c *= 0.9 + 0.2 * fbm(d * 6.0, 3, 41);
  return c;
}

Vec3 Scene::shade(const Vec3& d, const Hit& h) const {
  const Material& m = materials[h.material];
  const Vec3 albedo = m.albedo(h.s, h.u, h.p);
  const Vec3 origin = h.p + h.n * 1e-5;
  Vec3 light = ambient;
  Vec3 spec = Vec3::Zero();
  for (const auto& L : lights) {
    Vec3 to = L.position - h.p;
    const double dist2 = to.squaredNorm(), dist = std::sqrt(dist2);
    to /= dist;
    const double cosine = h.n.dot(to);
    if (cosine <= 0 || occluded(origin, to, dist)) continue;
    const Vec3 e = L.power * (cosine / (4.0 * kPi * dist2));
    light += e;
    if (m.specular > 0)
      spec +=
          L.power * (m.specular * std::pow(std::max(0.0, h.n.dot((to - d).normalized())), 40.0) / (4.0 * kPi * dist2));
  }
  if (sun_radiance.squaredNorm() > 0) {
    const double cosine = h.n.dot(sun_dir);
    if (cosine > 0 && !occluded(origin, sun_dir, 1e9)) {
      light += sun_radiance * cosine;
      if (m.specular > 0)
        spec += sun_radiance * m.specular * std::pow(std::max(0.0, h.n.dot((sun_dir - d).normalized())), 40.0);
    }
  }
  return albedo.cwiseProduct(light) + spec;
}

bool Scene::blocked(const Vec3& p, double margin) const {
  for (const auto& pr : prims) {
    if (pr.shape == Shape::Quad) {
      const Vec3 n = pr.e1.cross(pr.e2).normalized();
      const Vec3 rel = p - pr.p0;
      const double a = rel.dot(pr.e1) / pr.e1.squaredNorm(), b = rel.dot(pr.e2) / pr.e2.squaredNorm();
      if (std::fabs(rel.dot(n)) < margin && a > -0.05 && a < 1.05 && b > -0.05 && b < 1.05) return true;
      continue;
    }
    if ((p.array() >= (pr.bmin.array() - margin)).all() && (p.array() <= (pr.bmax.array() + margin)).all()) return true;
  }
  return false;
}

}  // namespace isplat::synth
