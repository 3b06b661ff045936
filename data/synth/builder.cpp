// Scene layouts and trajectories for the synthetic datasets.
#include "data/synth/builder.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace isplat::synth {
namespace {

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(uint64_t seed) : gen(seed) {}
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(gen); }
  bool chance(double p) { return uniform(0, 1) < p; }
  Vec3 color(double lo, double hi) { return Vec3(uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)); }
  template <class T>
  const T& pick(const std::vector<T>& v) {
    return v[static_cast<size_t>(integer(0, static_cast<int>(v.size()) - 1))];
  }
};

Mat3 yaw(double a) {
  return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix();
}

Primitive quad(const Vec3& p0, const Vec3& e1, const Vec3& e2, int mat) {
  Primitive p;
  p.shape = Shape::Quad;
  p.p0 = p0;
  p.e1 = e1;
  p.e2 = e2;
  p.material = mat;
  return p;
}

Primitive box(const Vec3& center, const Vec3& half, double yaw_angle, int mat) {
  Primitive p;
  p.shape = Shape::Box;
  p.p0 = center;
  p.half = half;
  p.R = yaw(yaw_angle);
  p.material = mat;
  return p;
}

Primitive sphere(const Vec3& c, double r, int mat) {
  Primitive p;
  p.shape = Shape::Sphere;
  p.p0 = c;
  p.radius = r;
  p.material = mat;
  return p;
}

// Cylinder from `base` along `axis` (unit) with the given radius and height.
Primitive cylinder(const Vec3& base, const Vec3& axis, double r, double h, int mat) {
  Primitive p;
  p.shape = Shape::Cylinder;
  p.p0 = base;
  const Vec3 z = axis.normalized();
  const Vec3 x = (std::fabs(z.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX()).cross(z).normalized();
  p.R.col(0) = x;
  p.R.col(1) = z.cross(x);
  p.R.col(2) = z;
  p.radius = r;
  p.height = h;
  p.material = mat;
  return p;
}

Material mat(Rng& rng, Pattern pattern, double scale, double lo, double hi, double spec = 0.0) {
  Material m;
  m.pattern = pattern;
  m.scale = scale;
  m.a = rng.color(lo, hi);
  m.b = (m.a * rng.uniform(0.25, 0.6)).eval();
  m.specular = spec;
  return m;
}

// A vertical wall from `origin` along the horizontal unit `along`, with an optional window hole.
void wall_with_window(Scene& s, const Vec3& origin, const Vec3& along, double length, double height, int material,
                      bool window, Rng& rng) {
  const Vec3 up(0, 0, height);
  if (!window) {
    s.add(quad(origin, along * length, up, material));
    return;
  }
  const double w = rng.uniform(1.0, std::min(2.5, length * 0.4));
  const double a0 = rng.uniform(0.5, length - w - 0.5), a1 = a0 + w;
  const double h0 = rng.uniform(0.7, 1.1), h1 = std::min(height - 0.3, h0 + rng.uniform(1.0, 1.6));
  const Vec3 z(0, 0, 1);
  s.add(quad(origin, along * a0, up, material));
  s.add(quad(origin + along * a1, along * (length - a1), up, material));
  s.add(quad(origin + along * a0, along * w, z * h0, material));
  s.add(quad(origin + along * a0 + z * h1, along * w, z * (height - h1), material));
}

void table(Scene& s, const Vec3& c, double yaw_angle, int top_mat, int leg_mat, Rng& rng) {
  const double w = rng.uniform(0.5, 0.8), d = rng.uniform(0.35, 0.5), h = rng.uniform(0.7, 0.78);
  s.add(box(c + Vec3(0, 0, h), Vec3(w, d, 0.025), yaw_angle, top_mat));
  const Mat3 R = yaw(yaw_angle);
  for (int sx : {-1, 1})
    for (int sy : {-1, 1}) {
      const Vec3 off = R * Vec3(sx * (w - 0.05), sy * (d - 0.05), 0);
      s.add(box(c + off + Vec3(0, 0, h / 2), Vec3(0.022, 0.022, h / 2), yaw_angle, leg_mat));  // thin legs
    }
}

void shelf(Scene& s, const Vec3& c, double yaw_angle, int mat, Rng& rng) {
  const double w = rng.uniform(0.4, 0.7), d = 0.18, h = rng.uniform(1.4, 2.0);
  const Mat3 R = yaw(yaw_angle);
  for (int sx : {-1, 1})
    s.add(box(c + R * Vec3(sx * w, 0, 0) + Vec3(0, 0, h / 2), Vec3(0.02, d, h / 2), yaw_angle, mat));
  const int boards = rng.integer(3, 5);
  for (int b = 0; b <= boards; ++b)
    s.add(box(c + Vec3(0, 0, 0.05 + b * (h - 0.1) / boards), Vec3(w, d, 0.015), yaw_angle, mat));
}

void lamp(Scene& s, const Vec3& base, int pole_mat, int shade_mat, Rng& rng) {
  const double h = rng.uniform(1.3, 1.7);
  s.add(cylinder(base, Vec3::UnitZ(), 0.015, h, pole_mat));  // thin structure
  s.add(sphere(base + Vec3(0, 0, h + 0.15), rng.uniform(0.12, 0.2), shade_mat));
}

void tree(Scene& s, const Vec3& base, int trunk_mat, int crown_mat, Rng& rng) {
  const double h = rng.uniform(2.0, 3.2);
  s.add(cylinder(base, Vec3::UnitZ(), rng.uniform(0.1, 0.18), h, trunk_mat));
  s.add(sphere(base + Vec3(0, 0, h + 0.6), rng.uniform(0.9, 1.4), crown_mat));
}

}  // namespace

Scene build_room(uint64_t seed) {
  Rng rng(seed);
  Scene s;
  s.style = "room";
  const double W = rng.uniform(5.0, 7.5), D = rng.uniform(7.5, 11.0), H = rng.uniform(2.6, 3.2);
  const int floor_m = s.add_material(
      mat(rng, rng.pick(std::vector<Pattern>{Pattern::Wood, Pattern::Tiles, Pattern::Checker, Pattern::Marble}),
          rng.uniform(0.4, 1.0), 0.35, 0.8, 0.1));
  const int ceil_m = s.add_material(mat(rng, Pattern::Noise, 2.0, 0.75, 0.9));
  const std::vector<Pattern> wall_patterns = {Pattern::Bricks, Pattern::Stripes, Pattern::Noise, Pattern::Grid};
  int wall_m[4];
  for (int k = 0; k < 4; ++k)
    wall_m[k] = s.add_material(mat(rng, rng.pick(wall_patterns), rng.uniform(0.25, 0.9), 0.45, 0.9));
  s.add(quad(Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(0, D, 0), floor_m));
  s.add(quad(Vec3(0, 0, H), Vec3(W, 0, 0), Vec3(0, D, 0), ceil_m));
  // Windows open onto the sky (no geometry: NaN depth, as in Hypersim); both end walls, which the
  // trajectories look at, always have one.
  const bool win_x0 = rng.chance(0.6), win_xW = !win_x0 || rng.chance(0.3);
  wall_with_window(s, Vec3(0, 0, 0), Vec3(0, 1, 0), D, H, wall_m[0], win_x0, rng);
  wall_with_window(s, Vec3(W, 0, 0), Vec3(0, 1, 0), D, H, wall_m[1], win_xW, rng);
  wall_with_window(s, Vec3(0, 0, 0), Vec3(1, 0, 0), W, H, wall_m[2], true, rng);
  wall_with_window(s, Vec3(0, D, 0), Vec3(1, 0, 0), W, H, wall_m[3], true, rng);

  const int wood = s.add_material(mat(rng, Pattern::Wood, rng.uniform(0.3, 0.7), 0.35, 0.7, 0.05));
  const int metal = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.15, 0.4, 0.4));
  const int fabric =
      s.add_material(mat(rng, rng.pick(std::vector<Pattern>{Pattern::Checker, Pattern::Stripes, Pattern::Dots}),
                         rng.uniform(0.08, 0.2), 0.3, 0.9));
  const int decor =
      s.add_material(mat(rng, rng.pick(std::vector<Pattern>{Pattern::Marble, Pattern::Dots, Pattern::Noise}),
                         rng.uniform(0.05, 0.2), 0.3, 0.95, 0.3));
  // Furniture stands along the side walls, leaving the central walkway free for the cameras.
  auto side_x = [&](bool left) { return left ? rng.uniform(0.5, W * 0.27) : rng.uniform(W * 0.73, W - 0.5); };
  const int pieces = rng.integer(5, 8);
  for (int k = 0; k < pieces; ++k) {
    const bool left = k % 2 == 0;
    const Vec3 c(side_x(left), rng.uniform(0.8, D - 0.8), 0);
    switch (rng.integer(0, 5)) {
      case 0:
        table(s, c, rng.uniform(-0.4, 0.4), wood, metal, rng);
        break;
      case 1:
        shelf(s, Vec3(left ? 0.25 : W - 0.25, c.y(), 0), kPi / 2, wood, rng);
        break;
      case 2: {
        const Vec3 half(rng.uniform(0.25, 0.5), rng.uniform(0.2, 0.45), rng.uniform(0.4, 0.9));
        s.add(box(c + Vec3(0, 0, half.z()), half, rng.uniform(-0.5, 0.5), rng.chance(0.5) ? fabric : wood));
        s.add(sphere(c + Vec3(0, 0, 2 * half.z() + 0.12), 0.12, decor));
        break;
      }
      case 3:
        lamp(s, c, metal, decor, rng);
        break;
      case 4:
        s.add(cylinder(c, Vec3::UnitZ(), rng.uniform(0.15, 0.3), H, rng.chance(0.5) ? decor : wall_m[0]));
        break;
      default: {  // a board leaning against the wall: a slanted plane
        const double len = rng.uniform(1.2, 2.0), width = rng.uniform(0.5, 1.0), lean = rng.uniform(0.25, 0.6);
        const double x_wall = left ? 0.02 : W - 0.02, sgn = left ? 1.0 : -1.0;
        s.add(quad(Vec3(x_wall + sgn * len * std::sin(lean), c.y(), 0), Vec3(0, width, 0),
                   Vec3(-sgn * len * std::sin(lean), 0, len * std::cos(lean)), fabric));
      }
    }
  }
  // Pictures on the walls (thin boxes with high-frequency patterns) and a thin rail.
  for (int k = 0; k < rng.integer(2, 4); ++k) {
    const int pm = s.add_material(
        mat(rng, rng.pick(std::vector<Pattern>{Pattern::Dots, Pattern::Checker, Pattern::Stripes, Pattern::Marble}),
            rng.uniform(0.04, 0.12), 0.1, 0.95));
    const bool on_end = rng.chance(0.5);
    const Vec3 half(rng.uniform(0.25, 0.6), 0.015, rng.uniform(0.2, 0.45));
    if (on_end)
      s.add(box(Vec3(rng.uniform(1.0, W - 1.0), D - 0.02, rng.uniform(1.3, H - 0.6)), half, 0.0, pm));
    else
      s.add(box(Vec3(rng.chance(0.5) ? 0.02 : W - 0.02, rng.uniform(1.0, D - 1.0), rng.uniform(1.3, H - 0.6)), half,
                kPi / 2, pm));
  }
  s.add(cylinder(Vec3(0.05, 0.3, H - 0.35), Vec3::UnitY(), 0.012, D - 0.6, metal));
  // A free-standing pillar near one end gives a strong depth discontinuity and disocclusions.
  s.add(box(Vec3(W / 2 + (rng.chance(0.5) ? -1.3 : 1.3), rng.chance(0.5) ? 1.2 : D - 1.2, H / 2), Vec3(0.2, 0.2, H / 2),
            0.0, wall_m[2]));

  const int n_lights = rng.integer(2, 3);
  for (int k = 0; k < n_lights; ++k)
    s.lights.push_back({Vec3(W * rng.uniform(0.3, 0.7), D * (k + 0.5) / n_lights, H - 0.6), rng.color(20.0, 32.0)});
  s.ambient = Vec3::Constant(rng.uniform(0.06, 0.12));
  s.sun_dir = Vec3(win_x0 ? -0.6 : 0.6, rng.uniform(-0.3, 0.3), 0.55).normalized();
  s.sun_radiance = Vec3(3.0, 2.8, 2.5) * rng.uniform(0.6, 1.0);
  s.walk_min = Vec3(W * 0.35, 0.9, 1.3);
  s.walk_max = Vec3(W * 0.65, D - 0.9, 1.7);
  s.focus_a = Vec3(W / 2, D - 0.1, 1.2);
  s.focus_b = Vec3(W / 2, 0.1, 1.2);
  s.build();
  return s;
}

Scene build_courtyard(uint64_t seed) {
  Rng rng(seed);
  Scene s;
  s.style = "courtyard";
  const double X = rng.uniform(14.0, 20.0), Y = rng.uniform(16.0, 22.0);
  const int ground = s.add_material(
      mat(rng, rng.pick(std::vector<Pattern>{Pattern::Tiles, Pattern::Bricks}), rng.uniform(0.5, 1.0), 0.4, 0.75));
  s.add(quad(Vec3(-15, -15, 0), Vec3(X + 30, 0, 0), Vec3(0, Y + 30, 0), ground));
  // Facades around the yard: big boxes with window grids.
  for (int side = 0; side < 4; ++side) {
    const int fm = s.add_material(mat(rng, Pattern::Grid, rng.uniform(1.2, 2.0), 0.5, 0.9));
    const double h = rng.uniform(6.0, 12.0);
    Vec3 c, half;
    if (side < 2) {
      c = Vec3(side == 0 ? -3.0 : X + 3.0, Y / 2, h / 2);
      half = Vec3(3.0, Y / 2 + 6.0, h / 2);
    } else {
      c = Vec3(X / 2, side == 2 ? -3.0 : Y + 3.0, h / 2);
      half = Vec3(X / 2, 3.0, h / 2);
    }
    s.add(box(c, half, 0.0, fm));
  }
  // An arcade: columns with a beam along one side.
  const int stone = s.add_material(mat(rng, Pattern::Marble, rng.uniform(0.3, 0.8), 0.6, 0.9, 0.1));
  const double ax = rng.chance(0.5) ? 2.0 : X - 2.0;
  for (double y = 2.0; y < Y - 1.5; y += rng.uniform(2.5, 3.5))
    s.add(cylinder(Vec3(ax, y, 0), Vec3::UnitZ(), 0.28, 4.0, stone));
  s.add(box(Vec3(ax, Y / 2, 4.25), Vec3(0.35, Y / 2 - 1.0, 0.25), 0.0, stone));
  // Fountain, trees, benches with thin legs, a sculpture.
  const int water = s.add_material(mat(rng, Pattern::Noise, 0.3, 0.2, 0.5, 0.5));
  const Vec3 fc(X * rng.uniform(0.4, 0.6), Y * rng.uniform(0.4, 0.6), 0);
  s.add(cylinder(fc, Vec3::UnitZ(), rng.uniform(1.2, 1.8), 0.6, stone));
  s.add(sphere(fc + Vec3(0, 0, 1.2), 0.45, water));
  const int trunk = s.add_material(mat(rng, Pattern::Wood, 0.2, 0.25, 0.45));
  const int leaves = s.add_material([&] {
    Material m = mat(rng, Pattern::Noise, 0.15, 0.1, 0.35);
    m.a = Vec3(rng.uniform(0.1, 0.25), rng.uniform(0.35, 0.6), rng.uniform(0.05, 0.2));
    return m;
  }());
  for (int k = 0; k < rng.integer(2, 4); ++k) {
    const Vec3 base(rng.chance(0.5) ? rng.uniform(1.0, 3.5) : rng.uniform(X - 3.5, X - 1.0), rng.uniform(2.0, Y - 2.0),
                    0);
    tree(s, base, trunk, leaves, rng);
  }
  const int metal = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.1, 0.3, 0.5));
  for (int k = 0; k < rng.integer(2, 3); ++k) {
    const Vec3 c(rng.uniform(2.5, X - 2.5), rng.chance(0.5) ? rng.uniform(1.5, 3.0) : rng.uniform(Y - 3.0, Y - 1.5), 0);
    table(s, c, rng.uniform(0, kPi), trunk, metal, rng);
  }
  for (int k = 0; k < 3; ++k)  // lamp posts: thin poles
    lamp(s, Vec3(rng.uniform(3.0, X - 3.0), rng.uniform(3.0, Y - 3.0), 0), metal, water, rng);
  s.ambient = Vec3(0.25, 0.28, 0.33) * rng.uniform(0.8, 1.2);
  s.sun_dir = Vec3(rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(0.5, 0.9)).normalized();
  s.sun_radiance = Vec3(2.8, 2.6, 2.3) * rng.uniform(0.8, 1.1);
  s.walk_min = Vec3(4.0, 3.0, 1.4);
  s.walk_max = Vec3(X - 4.0, Y - 3.0, 1.8);
  s.focus_a = Vec3(X / 2, Y + 0.5, 2.0);
  s.focus_b = Vec3(X / 2, -0.5, 2.0);
  s.build();
  return s;
}

Scene build_atrium(uint64_t seed) {
  Rng rng(seed);
  Scene s;
  s.style = "atrium";
  const double W = rng.uniform(12.0, 16.0), D = rng.uniform(18.0, 24.0), H = rng.uniform(7.0, 9.0);
  const int floor_m = s.add_material(mat(rng, Pattern::Marble, rng.uniform(0.6, 1.2), 0.6, 0.9, 0.3));
  const int concrete = s.add_material(mat(rng, Pattern::Noise, rng.uniform(0.5, 1.5), 0.45, 0.7));
  const int panel = s.add_material(mat(rng, Pattern::Grid, rng.uniform(0.8, 1.5), 0.4, 0.8));
  s.add(quad(Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(0, D, 0), floor_m));
  // Ceiling with a skylight opening (sky, invalid depth).
  const double sx0 = W * 0.3, sx1 = W * 0.7, sy0 = D * 0.3, sy1 = D * 0.7;
  s.add(quad(Vec3(0, 0, H), Vec3(sx0, 0, 0), Vec3(0, D, 0), concrete));
  s.add(quad(Vec3(sx1, 0, H), Vec3(W - sx1, 0, 0), Vec3(0, D, 0), concrete));
  s.add(quad(Vec3(sx0, 0, H), Vec3(sx1 - sx0, 0, 0), Vec3(0, sy0, 0), concrete));
  s.add(quad(Vec3(sx0, sy1, H), Vec3(sx1 - sx0, 0, 0), Vec3(0, D - sy1, 0), concrete));
  s.add(quad(Vec3(0, 0, 0), Vec3(0, D, 0), Vec3(0, 0, H), panel));
  s.add(quad(Vec3(W, 0, 0), Vec3(0, D, 0), Vec3(0, 0, H), panel));
  s.add(quad(Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(0, 0, H), concrete));
  s.add(quad(Vec3(0, D, 0), Vec3(W, 0, 0), Vec3(0, 0, H), concrete));
  // Balconies along both long walls, with thin railings.
  const int metal = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.15, 0.35, 0.6));
  const double bh = rng.uniform(3.2, 4.0);
  for (int side : {0, 1}) {
    const double x = side == 0 ? 1.2 : W - 1.2;
    s.add(box(Vec3(x, D / 2, bh), Vec3(1.2, D / 2 - 0.5, 0.12), 0.0, concrete));
    const double rx = side == 0 ? 2.35 : W - 2.35;
    s.add(cylinder(Vec3(rx, 0.6, bh + 1.0), Vec3::UnitY(), 0.025, D - 1.2, metal));
    for (double y = 0.8; y < D - 0.6; y += 1.2) s.add(cylinder(Vec3(rx, y, bh), Vec3::UnitZ(), 0.015, 1.0, metal));
  }
  const int col = s.add_material(mat(rng, Pattern::Marble, 0.4, 0.7, 0.95, 0.2));
  for (double y = 3.0; y < D - 2.0; y += rng.uniform(4.0, 5.0))
    for (double x : {3.2, W - 3.2}) s.add(cylinder(Vec3(x, y, 0), Vec3::UnitZ(), 0.35, bh, col));
  const int plant = s.add_material([&] {
    Material m = mat(rng, Pattern::Noise, 0.12, 0.1, 0.4);
    m.a = Vec3(0.15, rng.uniform(0.4, 0.6), 0.15);
    return m;
  }());
  for (int k = 0; k < rng.integer(3, 5); ++k) {
    const Vec3 c(rng.chance(0.5) ? rng.uniform(4.2, W * 0.35) : rng.uniform(W * 0.65, W - 4.2),
                 rng.uniform(2.0, D - 2.0), 0);
    s.add(box(c + Vec3(0, 0, 0.35), Vec3(0.5, 0.5, 0.35), rng.uniform(0, kPi), concrete));
    s.add(sphere(c + Vec3(0, 0, 1.2), rng.uniform(0.45, 0.7), plant));
  }
  for (int k = 0; k < 4; ++k)
    s.lights.push_back({Vec3(W * (k % 2 ? 0.25 : 0.75), D * (k / 2 ? 0.7 : 0.3), bh - 0.4), rng.color(60.0, 90.0)});
  s.ambient = Vec3::Constant(rng.uniform(0.1, 0.16));
  s.sun_dir = Vec3(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 1.0).normalized();
  s.sun_radiance = Vec3(2.6, 2.5, 2.3);
  s.walk_min = Vec3(W * 0.35, 1.5, 1.4);
  s.walk_max = Vec3(W * 0.65, D - 1.5, 1.8);
  s.focus_a = Vec3(W / 2, D - 0.2, 2.5);
  s.focus_b = Vec3(W / 2, 0.2, 2.5);
  s.build();
  return s;
}

Scene build_desk(uint64_t seed) {
  // A tabletop seen from close by: depths of 0.3-3 m, small objects, thin parts, a wall behind.
  Rng rng(seed);
  Scene s;
  s.style = "desk";
  const double W = rng.uniform(2.6, 3.4), D = rng.uniform(2.4, 3.0), H = rng.uniform(2.4, 2.8);
  const int floor_m = s.add_material(
      mat(rng, rng.pick(std::vector<Pattern>{Pattern::Wood, Pattern::Tiles}), rng.uniform(0.3, 0.6), 0.35, 0.8));
  const int wall_m = s.add_material(
      mat(rng, rng.pick(std::vector<Pattern>{Pattern::Noise, Pattern::Stripes}), rng.uniform(0.2, 0.6), 0.5, 0.9));
  s.add(quad(Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(0, D, 0), floor_m));
  s.add(quad(Vec3(0, 0, H), Vec3(0, D, 0), Vec3(W, 0, 0), wall_m));
  s.add(quad(Vec3(0, D, 0), Vec3(W, 0, 0), Vec3(0, 0, H), wall_m));
  s.add(quad(Vec3(0, 0, 0), Vec3(0, 0, H), Vec3(0, D, 0), wall_m));
  s.add(quad(Vec3(W, 0, 0), Vec3(0, D, 0), Vec3(0, 0, H), wall_m));
  s.add(quad(Vec3(0, 0, 0), Vec3(0, 0, H), Vec3(W, 0, 0), wall_m));
  // The desk against the far wall, its top at 0.72-0.78 m.
  const int top =
      s.add_material(mat(rng, rng.pick(std::vector<Pattern>{Pattern::Wood, Pattern::Marble, Pattern::Solid}),
                         rng.uniform(0.08, 0.3), 0.3, 0.85, 0.15));
  const double tw = rng.uniform(0.7, 1.0), td = rng.uniform(0.35, 0.45), th = rng.uniform(0.72, 0.78);
  const Vec3 tc(W / 2, D - td - 0.05, 0);
  s.add(box(tc + Vec3(0, 0, th), Vec3(tw, td, 0.02), 0.0, top));
  for (int sx : {-1, 1}) s.add(box(tc + Vec3(sx * (tw - 0.04), 0, th / 2), Vec3(0.02, td - 0.03, th / 2), 0.0, top));
  // Objects: books (thin boxes), mugs (cylinders), balls, a monitor, a pencil cup with thin pencils.
  const std::vector<Pattern> fine = {Pattern::Dots, Pattern::Checker, Pattern::Stripes, Pattern::Noise, Pattern::Grid};
  for (int k = 0; k < rng.integer(6, 11); ++k) {
    const int m = s.add_material(mat(rng, rng.pick(fine), rng.uniform(0.01, 0.05), 0.1, 0.95, rng.uniform(0.0, 0.3)));
    const Vec3 p(tc.x() + rng.uniform(-tw + 0.1, tw - 0.1), tc.y() + rng.uniform(-td + 0.08, td - 0.08), th + 0.02);
    switch (rng.integer(0, 3)) {
      case 0: {
        const Vec3 half(rng.uniform(0.05, 0.12), rng.uniform(0.07, 0.15), rng.uniform(0.01, 0.04));
        s.add(box(p + Vec3(0, 0, half.z()), half, rng.uniform(0, kPi), m));
        break;
      }
      case 1:
        s.add(cylinder(p, Vec3::UnitZ(), rng.uniform(0.03, 0.05), rng.uniform(0.08, 0.12), m));
        break;
      case 2: {
        const double r = rng.uniform(0.03, 0.08);
        s.add(sphere(p + Vec3(0, 0, r), r, m));
        break;
      }
      default:
        for (int q = 0; q < 4; ++q)
          s.add(cylinder(p + Vec3(rng.uniform(-0.02, 0.02), rng.uniform(-0.02, 0.02), 0),
                         Vec3(rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2), 1).normalized(), 0.004, 0.16, m));
    }
  }
  const int screen = s.add_material(mat(rng, Pattern::Noise, 0.05, 0.02, 0.3, 0.4));
  s.add(box(tc + Vec3(rng.uniform(-0.3, 0.3), td * 0.5, th + 0.32), Vec3(0.3, 0.015, 0.18), rng.uniform(-0.2, 0.2),
            screen));
  s.lights.push_back({Vec3(W * rng.uniform(0.3, 0.7), D * 0.5, H - 0.3), rng.color(6.0, 12.0)});
  s.lights.push_back({tc + Vec3(rng.uniform(-0.5, 0.5), -0.2, th + 0.6), rng.color(0.5, 1.5)});  // desk lamp
  s.ambient = Vec3::Constant(rng.uniform(0.05, 0.15));
  // Cameras 0.35-1.2 m in front of the desk, at sitting or standing eye height, looking at its top.
  s.walk_min = Vec3(tc.x() - 0.6, tc.y() - td - 1.0, 0.95);
  s.walk_max = Vec3(tc.x() + 0.6, tc.y() - td - 0.3, 1.45);
  s.focus_a = tc + Vec3(rng.uniform(-0.2, 0.2), 0, th + 0.05);
  s.focus_b = tc + Vec3(rng.uniform(-0.2, 0.2), 0.1, th + 0.1);
  s.build();
  return s;
}

Scene build_street(uint64_t seed) {
  // An urban street canyon: facades of varied height on both sides, parked cars, poles and trees, the
  // street running 60-120 m into the distance and open sky: depths from 2 m to beyond 60 m.
  Rng rng(seed);
  Scene s;
  s.style = "street";
  const double L = rng.uniform(60.0, 120.0), w = rng.uniform(10.0, 18.0);
  const int road = s.add_material(mat(rng, Pattern::Noise, rng.uniform(0.5, 2.0), 0.15, 0.35));
  const int pavement = s.add_material(
      mat(rng, rng.pick(std::vector<Pattern>{Pattern::Tiles, Pattern::Bricks}), rng.uniform(0.4, 0.9), 0.4, 0.75));
  s.add(quad(Vec3(-w / 2, -20, 0), Vec3(w, 0, 0), Vec3(0, L + 40, 0), road));
  for (int side : {-1, 1}) {
    s.add(quad(Vec3(side < 0 ? -w / 2 - 3.0 : w / 2, -20, 0.12), Vec3(3.0, 0, 0), Vec3(0, L + 40, 0), pavement));
    // Facades: consecutive buildings with their own height, setback and window grid.
    for (double y = -20; y < L + 20;) {
      const double len = rng.uniform(6.0, 16.0), h = rng.uniform(6.0, 30.0), setback = rng.uniform(0.0, 1.5);
      const int fm = s.add_material(
          mat(rng, rng.pick(std::vector<Pattern>{Pattern::Grid, Pattern::Bricks}), rng.uniform(0.8, 2.5), 0.3, 0.9));
      const double x = side * (w / 2 + 3.0 + setback + 5.0);
      s.add(box(Vec3(x, y + len / 2, h / 2), Vec3(5.0, len / 2 - 0.05, h / 2), 0.0, fm));
      y += len;
    }
  }
  // A far building closes the street in half of the scenes; the others open onto the sky.
  if (rng.chance(0.5)) {
    const int fm = s.add_material(mat(rng, Pattern::Grid, rng.uniform(1.5, 3.0), 0.3, 0.9));
    s.add(box(Vec3(0, L + 25, 15), Vec3(w, 5, 15), 0.0, fm));
  }
  const int metal = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.1, 0.4, 0.5));
  const int trunk = s.add_material(mat(rng, Pattern::Wood, 0.2, 0.25, 0.45));
  const int leaves = s.add_material([&] {
    Material m = mat(rng, Pattern::Noise, 0.2, 0.1, 0.35);
    m.a = Vec3(rng.uniform(0.1, 0.25), rng.uniform(0.35, 0.6), rng.uniform(0.05, 0.2));
    return m;
  }());
  for (double y = rng.uniform(0, 10); y < L; y += rng.uniform(8.0, 16.0)) {
    const int side = rng.chance(0.5) ? -1 : 1;
    if (rng.chance(0.5))
      tree(s, Vec3(side * (w / 2 + 1.5), y, 0.12), trunk, leaves, rng);
    else
      s.add(cylinder(Vec3(side * (w / 2 + 0.4), y, 0.12), Vec3::UnitZ(), 0.06, rng.uniform(4.0, 7.0), metal));
  }
  for (double y = rng.uniform(0, 8); y < L; y += rng.uniform(5.0, 14.0)) {  // parked cars: body and cabin
    const int car = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.1, 0.9, 0.4));
    const double x = (rng.chance(0.5) ? -1 : 1) * (w / 2 - 1.2);
    s.add(box(Vec3(x, y, 0.55), Vec3(0.9, 2.2, 0.4), rng.uniform(-0.05, 0.05), car));
    s.add(box(Vec3(x, y - 0.2, 1.2), Vec3(0.8, 1.2, 0.3), 0.0, car));
  }
  s.ambient = Vec3(0.22, 0.25, 0.3) * rng.uniform(0.6, 1.3);
  s.sun_dir = Vec3(rng.uniform(-0.7, 0.7), rng.uniform(-0.7, 0.7), rng.uniform(0.3, 0.9)).normalized();
  s.sun_radiance = Vec3(2.8, 2.6, 2.3) * rng.uniform(0.5, 1.2);
  s.sky_zenith = Vec3(rng.uniform(0.15, 0.35), rng.uniform(0.3, 0.5), rng.uniform(0.7, 0.95));
  s.walk_min = Vec3(-w / 2 + 1.0, 0.0, 1.4);
  s.walk_max = Vec3(w / 2 - 1.0, L * 0.6, 1.9);
  s.focus_a = Vec3(rng.uniform(-2, 2), L + 30, rng.uniform(2.0, 6.0));
  s.focus_b = Vec3(rng.uniform(-2, 2), -30, rng.uniform(2.0, 6.0));
  s.build();
  return s;
}

Scene build_hall(uint64_t seed) {
  // A warehouse or sports hall: one large interior, 20-45 m long and 6-14 m high, a column grid, rows of
  // pallet racks and stacked crates, high strip windows onto the sky and hanging lamps: indoor light and
  // texture at depths between a room's and a street's.
  Rng rng(seed);
  Scene s;
  s.style = "hall";
  const double W = rng.uniform(14.0, 30.0), D = rng.uniform(20.0, 45.0), H = rng.uniform(6.0, 14.0);
  const int floor_m =
      s.add_material(mat(rng, rng.pick(std::vector<Pattern>{Pattern::Noise, Pattern::Tiles, Pattern::Stripes}),
                         rng.uniform(1.0, 3.0), 0.3, 0.7, 0.15));
  const int roof = s.add_material(mat(rng, Pattern::Stripes, rng.uniform(0.6, 1.2), 0.5, 0.85));
  const int wall =
      s.add_material(mat(rng, rng.pick(std::vector<Pattern>{Pattern::Stripes, Pattern::Bricks, Pattern::Noise}),
                         rng.uniform(0.5, 1.5), 0.35, 0.85));
  s.add(quad(Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(0, D, 0), floor_m));
  s.add(quad(Vec3(0, 0, H), Vec3(W, 0, 0), Vec3(0, D, 0), roof));
  // Long walls with a strip of high windows (sky behind: invalid depth); solid end walls.
  const double w0 = H * rng.uniform(0.6, 0.7), w1 = std::min(H - 0.4, w0 + rng.uniform(1.0, 2.0));
  for (double x : {0.0, W}) {
    s.add(quad(Vec3(x, 0, 0), Vec3(0, D, 0), Vec3(0, 0, w0), wall));
    s.add(quad(Vec3(x, 0, w1), Vec3(0, D, 0), Vec3(0, 0, H - w1), wall));
    for (double y = 0; y < D; y += 6.0)  // mullions across the window strip
      s.add(box(Vec3(x, y, (w0 + w1) / 2), Vec3(0.08, 0.08, (w1 - w0) / 2), 0.0, wall));
  }
  for (double y : {0.0, D}) s.add(quad(Vec3(0, y, 0), Vec3(W, 0, 0), Vec3(0, 0, H), wall));
  // Steel columns on a grid, and roof beams across.
  const int steel = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.2, 0.6, 0.4));
  const double bay = rng.uniform(6.0, 9.0);
  for (double y = bay; y < D - 1.0; y += bay) {
    for (double x : {W / 3, 2 * W / 3}) s.add(box(Vec3(x, y, H / 2), Vec3(0.18, 0.18, H / 2), 0.0, steel));
    s.add(box(Vec3(W / 2, y, H - 0.4), Vec3(W / 2, 0.12, 0.3), 0.0, steel));
  }
  // Pallet racks along the long walls and crates on the floor (the clutter the camera walks past).
  const int rack = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.3, 0.8, 0.2));
  const int crate = s.add_material(mat(rng, Pattern::Wood, rng.uniform(0.2, 0.5), 0.35, 0.7));
  const double rack_h = std::min(H - 1.5, rng.uniform(3.5, 6.0));
  for (double x : {1.2, W - 1.2}) {
    if (!rng.chance(0.8)) continue;
    for (double y = 2.0; y < D - 3.0; y += 2.8) {
      for (int level = 0; level <= 3; ++level)
        s.add(box(Vec3(x, y + 1.4, level * rack_h / 3 + 0.05), Vec3(0.6, 1.35, 0.05), 0.0, rack));
      s.add(box(Vec3(x, y, rack_h / 2), Vec3(0.6, 0.05, rack_h / 2), 0.0, rack));
      for (int level = 0; level < 3; ++level)
        if (rng.chance(0.6))
          s.add(box(Vec3(x, y + 1.4, level * rack_h / 3 + 0.45), Vec3(0.5, rng.uniform(0.5, 1.2), 0.38), 0.0, crate));
    }
  }
  for (int k = 0; k < rng.integer(4, 9); ++k) {
    const Vec3 c(rng.uniform(3.0, W - 3.0), rng.uniform(3.0, D - 3.0), 0);
    const int stack = rng.integer(1, 3);
    for (int l = 0; l < stack; ++l)
      s.add(box(c + Vec3(0, 0, 0.45 + 0.9 * l), Vec3(0.6, 0.6, 0.44), rng.uniform(0, kPi), crate));
  }
  // Hanging lamps.
  const int shade = s.add_material(mat(rng, Pattern::Solid, 1.0, 0.7, 0.95, 0.5));
  for (double y = bay / 2; y < D; y += bay) {
    const Vec3 c(W / 2 + rng.uniform(-1.0, 1.0), y, H - 1.5);
    s.add(cylinder(c, Vec3::UnitZ(), 0.01, 1.1, steel));
    s.add(sphere(c, 0.3, shade));
    s.lights.push_back({c - Vec3(0, 0, 0.5), rng.color(80.0, 160.0)});
  }
  s.ambient = Vec3::Constant(rng.uniform(0.08, 0.16));
  s.sun_dir = Vec3(rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(0.4, 0.9)).normalized();
  s.sun_radiance = Vec3(2.6, 2.5, 2.3) * rng.uniform(0.6, 1.1);
  s.walk_min = Vec3(W * 0.3, 2.0, 1.4);
  s.walk_max = Vec3(W * 0.7, D - 2.0, 1.9);
  s.focus_a = Vec3(W / 2, D - 0.2, rng.uniform(2.0, 4.0));
  s.focus_b = Vec3(W / 2, 0.2, rng.uniform(2.0, 4.0));
  s.build();
  return s;
}

Scene build_clutter(uint64_t seed) {
  // Domain randomization: primitives of random shape, size, pose and material (some floating, some tilted) over
  // a ground plane, enclosed by walls or open to the sky, at a scene scale drawn from a desk's to a street's. No
  // layout repeats, so a depth net cannot learn "rooms look like this"; it has to read shading, texture
  // gradients, occlusion and size.
  Rng rng(seed);
  Scene s;
  s.style = "clutter";
  const double S = std::exp(rng.uniform(std::log(0.4), std::log(6.0)));  // scene scale: 1 = a room
  const double W = 12.0 * S, D = 24.0 * S;
  const std::vector<Pattern> all = {Pattern::Solid, Pattern::Checker, Pattern::Stripes, Pattern::Noise, Pattern::Bricks,
                                    Pattern::Wood,  Pattern::Tiles,   Pattern::Marble,  Pattern::Dots,  Pattern::Grid};
  auto random_material = [&](double size) {
    return s.add_material(mat(rng, rng.pick(all), size * rng.uniform(0.05, 0.6), 0.05, 0.95, rng.uniform(0.0, 0.5)));
  };
  s.add(quad(Vec3(-W / 2, -4.0 * S, 0), Vec3(W, 0, 0), Vec3(0, D + 4.0 * S, 0), random_material(4.0 * S)));
  // Cameras stand in the first eighth of the floor; objects fill the rest, the nearest a few decimetres away.
  s.walk_min = Vec3(-W / 8, -S, 1.0 * std::clamp(S, 0.6, 1.5));
  s.walk_max = Vec3(W / 8, 2.0 * S, 1.9 * std::clamp(S, 0.6, 1.5));
  const double enclosure = rng.uniform(0, 1), H = std::max(S * rng.uniform(2.5, 6.0), s.walk_max.z() + 0.5);
  if (enclosure < 0.4) {  // closed: four walls and a ceiling
    const int wall = random_material(2.0 * S);
    s.add(quad(Vec3(-W / 2, -4.0 * S, 0), Vec3(0, D + 4.0 * S, 0), Vec3(0, 0, H), wall));
    s.add(quad(Vec3(W / 2, -4.0 * S, 0), Vec3(0, 0, H), Vec3(0, D + 4.0 * S, 0), wall));
    s.add(quad(Vec3(-W / 2, D, 0), Vec3(W, 0, 0), Vec3(0, 0, H), wall));
    s.add(quad(Vec3(-W / 2, -4.0 * S, 0), Vec3(0, 0, H), Vec3(W, 0, 0), wall));
    s.add(quad(Vec3(-W / 2, -4.0 * S, H), Vec3(0, D + 4.0 * S, 0), Vec3(W, 0, 0), random_material(2.0 * S)));
  } else if (enclosure < 0.7) {  // a far wall, sky above it
    s.add(quad(Vec3(-W / 2, D, 0), Vec3(W, 0, 0), Vec3(0, 0, H), random_material(2.0 * S)));
  }
  // An object reaching back into the walk box (a long tilted cylinder, a rotated box) is pushed out of it.
  auto place = [&](Primitive p) {
    p.finalize();
    p.p0.y() += std::max(0.0, s.walk_max.y() + 0.2 * S - p.bmin.y());
    s.add(p);
  };
  for (int k = 0, n = rng.integer(25, 60); k < n; ++k) {
    const double size = S * std::exp(rng.uniform(std::log(0.08), std::log(1.5)));
    const Vec3 c(rng.uniform(-W / 2, W / 2), rng.uniform(s.walk_max.y() + size + 0.3, D - size),
                 rng.chance(0.6) ? 0.0 : rng.uniform(0.3 * S, 3.0 * S));  // resting or floating
    const int m = random_material(size);
    switch (rng.integer(0, 2)) {
      case 0: {
        Primitive b = box(Vec3::Zero(), size * Vec3(rng.uniform(0.2, 1), rng.uniform(0.2, 1), rng.uniform(0.2, 1)),
                          rng.uniform(0, kPi), m);
        if (rng.chance(0.4))  // tilted
          b.R = (b.R * Eigen::AngleAxisd(rng.uniform(-0.8, 0.8), Vec3::UnitX()).toRotationMatrix()).eval();
        b.p0 = c + Vec3(0, 0, (b.R.cwiseAbs() * b.half).z());
        place(b);
        break;
      }
      case 1: {
        const double r = size * rng.uniform(0.3, 1.0);
        place(sphere(c + Vec3(0, 0, r), r, m));
        break;
      }
      default: {
        const Vec3 axis = rng.chance(0.5)
                              ? Vec3::UnitZ()
                              : Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.1, 1)).normalized();
        place(cylinder(c, axis, size * rng.uniform(0.05, 0.5), size * rng.uniform(0.5, 2.5), m));
      }
    }
  }
  if (enclosure < 0.4) {
    for (int k = 0, n = rng.integer(1, 4); k < n; ++k)
      s.lights.push_back(
          {Vec3(rng.uniform(-W / 3, W / 3), rng.uniform(0, D), H - 0.2 * S), rng.color(20.0, 60.0) * S * S});
  } else {
    s.sun_dir = Vec3(rng.uniform(-0.7, 0.7), rng.uniform(-0.7, 0.7), rng.uniform(0.2, 0.9)).normalized();
    s.sun_radiance = Vec3(2.8, 2.6, 2.3) * rng.uniform(0.5, 1.2);
    s.sky_zenith = Vec3(rng.uniform(0.15, 0.45), rng.uniform(0.3, 0.6), rng.uniform(0.6, 0.95));
  }
  s.ambient = Vec3::Constant(rng.uniform(0.06, 0.25));
  s.focus_a = Vec3(rng.uniform(-W / 4, W / 4), D * rng.uniform(0.4, 0.9), rng.uniform(0.0, 1.5 * S));
  s.focus_b = Vec3(rng.uniform(-W / 3, W / 3), D * rng.uniform(0.2, 0.5), rng.uniform(0.0, 1.0 * S));
  s.build();
  return s;
}

Scene build_scene(const std::string& style, uint64_t seed) {
  if (style == "room") return build_room(seed);
  if (style == "courtyard") return build_courtyard(seed);
  if (style == "atrium") return build_atrium(seed);
  if (style == "desk") return build_desk(seed);
  if (style == "street") return build_street(seed);
  if (style == "hall") return build_hall(seed);
  if (style == "clutter") return build_clutter(seed);
  fail("unknown scene style '", style, "' (room | courtyard | atrium | desk | street | hall | clutter)");
}

Mat3 look_rotation(const Vec3& center, const Vec3& target) {
  const Vec3 f = (target - center).normalized();
  Vec3 r = f.cross(Vec3::UnitZ());
  if (r.norm() < 1e-6) r = Vec3::UnitX();
  r.normalize();
  const Vec3 d = f.cross(r);
  Mat3 R;
  R.col(0) = r;
  R.col(1) = d;
  R.col(2) = f;
  return R;
}

std::vector<CameraPose> make_trajectory(const Scene& scene, int frames, uint64_t seed, double min_step,
                                        double max_step) {
  Rng rng(seed);
  const Vec3 lo = scene.walk_min, hi = scene.walk_max;
  // Walk back and forth along the long axis (y) while looking towards one end.
  const bool towards_a = rng.chance(0.5);
  const Vec3 focus = towards_a ? scene.focus_a : scene.focus_b;
  auto free_point = [&](double y_frac) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      Vec3 p(rng.uniform(lo.x(), hi.x()),
             lo.y() + (hi.y() - lo.y()) * std::clamp(y_frac + rng.uniform(-0.1, 0.1), 0.0, 1.0),
             rng.uniform(lo.z(), hi.z()));
      if (!scene.blocked(p, 0.35)) return p;
    }
    return Vec3(((lo + hi) / 2).eval());
  };
  // Start at the end facing away from the focus, so the camera looks across the scene.
  std::vector<Vec3> waypoints = {free_point(towards_a ? 0.0 : 1.0)};
  for (int k = 1; k < 8; ++k) {
    const double frac = (k % 2) ? 0.55 : 0.05;
    waypoints.push_back(free_point(towards_a ? frac : 1.0 - frac));
  }
  std::vector<CameraPose> out;
  Vec3 pos = waypoints[0];
  size_t wp = 1;
  // Step length per block of 8 frames, stratified over [min_step, max_step] on a log scale and shuffled,
  // so every trajectory mixes centimetre steps with metre-scale ones (all baseline bins get pairs).
  constexpr int kBlock = 8, kStrata = 5;
  std::vector<int> strata;
  auto next_step = [&]() {
    if (strata.empty()) {
      for (int k = 0; k < kStrata; ++k) strata.push_back(k);
      std::shuffle(strata.begin(), strata.end(), rng.gen);
    }
    const double t = (strata.back() + rng.uniform(0.0, 1.0)) / kStrata;
    strata.pop_back();
    return std::exp(std::log(min_step) + t * (std::log(max_step) - std::log(min_step)));
  };
  double step = next_step();
  double look_phase = rng.uniform(0, 2 * kPi);
  for (int i = 0; i < frames; ++i) {
    // Gaze drifts smoothly around the focus point.
    const Vec3 target =
        focus + Vec3(2.0 * std::sin(look_phase + 0.23 * i), 0, 0.6 * std::sin(0.7 * look_phase + 0.17 * i));
    out.push_back({pos, look_rotation(pos, target)});
    if ((i + 1) % kBlock == 0) step = next_step();
    // Advance along the waypoint polyline by `step`.
    double remaining = step;
    while (remaining > 0 && wp < waypoints.size()) {
      const Vec3 to = waypoints[wp] - pos;
      const double len = to.norm();
      if (len > remaining) {
        const Vec3 next = pos + to * (remaining / len);
        if (!scene.blocked(next, 0.2)) pos = next;
        remaining = 0;
      } else {
        pos = waypoints[wp++];
        remaining -= len;
      }
    }
    if (wp >= waypoints.size()) waypoints.push_back(free_point(rng.uniform(0.0, 1.0)));
  }
  return out;
}

}  // namespace isplat::synth
