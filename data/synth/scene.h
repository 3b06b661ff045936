// Procedural scenes for the synthetic datasets: primitives with procedural materials, lights, a BVH,
// and ray queries. Everything is deterministic; no external renderer.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace isplat::synth {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

inline constexpr double kPi = 3.14159265358979323846;

enum class Pattern { Solid, Checker, Stripes, Noise, Bricks, Wood, Tiles, Marble, Dots, Grid };

struct Material {
  Vec3 a = Vec3(0.7, 0.7, 0.7), b = Vec3(0.3, 0.3, 0.3);
  Pattern pattern = Pattern::Solid;
  double scale = 1.0;                                    // pattern period in metres
  double specular = 0.0;                                 // Blinn-Phong weight
  Vec3 albedo(double s, double t, const Vec3& p) const;  // (s, t): surface coordinates in metres
};

enum class Shape { Quad, Box, Sphere, Cylinder };

struct Primitive {
  Shape shape = Shape::Quad;
  int material = 0;
  Vec3 p0 = Vec3::Zero();                     // quad corner | box/sphere centre | cylinder base centre
  Vec3 e1 = Vec3::Zero(), e2 = Vec3::Zero();  // quad edges
  Vec3 half = Vec3::Zero();                   // box half extents (local axes)
  Mat3 R = Mat3::Identity();                  // box/cylinder: world-from-local rotation (cylinder axis = local z)
  double radius = 0, height = 0;
  Vec3 bmin = Vec3::Zero(), bmax = Vec3::Zero();  // world bounds, filled by finalize()
  void finalize();
};

struct PointLight {
  Vec3 position;
  Vec3 power;  // radiant intensity per channel
};

struct Hit {
  double t = 0;
  Vec3 p, n;  // position and geometric normal (facing the ray)
  double s = 0, u = 0;
  int material = -1;
};

struct Scene {
  std::string style;  // "room", "courtyard", "atrium", "desk", "street"
  std::vector<Primitive> prims;
  std::vector<Material> materials;
  std::vector<PointLight> lights;
  Vec3 sun_dir = Vec3(0.3, 0.2, 0.9).normalized();  // towards the sun
  Vec3 sun_radiance = Vec3::Zero();
  Vec3 ambient = Vec3(0.05, 0.05, 0.05);
  Vec3 sky_zenith = Vec3(0.25, 0.45, 0.9), sky_horizon = Vec3(0.8, 0.85, 0.95);
  Vec3 walk_min, walk_max;  // where cameras may stand
  Vec3 focus_a, focus_b;    // two far ends trajectories look towards

  int add_material(const Material& m);
  void add(Primitive p);
  void build();  // builds the BVH; call after adding primitives

  bool intersect(const Vec3& o, const Vec3& d, double tmax, Hit& hit) const;  // d unit length
  bool occluded(const Vec3& o, const Vec3& d, double tmax) const;
  Vec3 sky(const Vec3& d) const;
  Vec3 shade(const Vec3& d, const Hit& hit) const;   // outgoing linear radiance towards -d
  bool blocked(const Vec3& p, double margin) const;  // p lies inside (or near) a solid

 private:
  struct Node {
    Vec3 bmin, bmax;
    int left = -1, right = -1, first = 0, count = 0;
  };
  std::vector<Node> nodes_;
  std::vector<int> order_;
  int build_node(int first, int count);
  template <bool AnyHit>
  bool traverse(const Vec3& o, const Vec3& d, double tmax, Hit* hit) const;
};

// Deterministic hashing noise in [0, 1).
double hash01(int64_t x, int64_t y, int64_t z, uint64_t salt);
double value_noise(const Vec3& p, uint64_t salt);
double fbm(const Vec3& p, int octaves, uint64_t salt);

}  // namespace isplat::synth
