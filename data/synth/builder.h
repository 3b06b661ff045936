// Random scene layouts (rooms, desks, streets, halls and random clutter for training; courtyards and atria for
// evaluation) and camera trajectories that walk through them with baselines from centimetres to metres.
#pragma once
#include <cstdint>
#include <vector>

#include "data/synth/scene.h"

namespace isplat::synth {

Scene build_room(uint64_t seed);       // Hypersim-style interiors: textured walls, windows, furniture
Scene build_courtyard(uint64_t seed);  // outdoor yard: facades, arcades, trees, sky
Scene build_atrium(uint64_t seed);     // tall hall: marble, balconies with railings, columns, skylight
Scene build_desk(uint64_t seed);       // a tabletop from close by: 0.3-3 m, small and thin objects
Scene build_street(uint64_t seed);     // an urban street canyon: facades, cars, poles, sky; 2 m to beyond 60 m
// Domain randomization: random primitives at a random scale, 0.3 m to 150 m.
Scene build_clutter(uint64_t seed);
Scene build_scene(const std::string& style, uint64_t seed);

struct CameraPose {
  Vec3 center;
  Mat3 R_wc;  // world-from-camera, OpenCV axes: columns right, down, forward
};

// `frames` poses along a smooth walk through scene.walk_min..walk_max, looking towards one of the
// scene's focus points. Step lengths change every 8 frames, stratified on a log scale between min_step
// and max_step, so windows of 10 frames span baselines from centimetres to several metres.
std::vector<CameraPose> make_trajectory(const Scene& scene, int frames, uint64_t seed, double min_step = 0.04,
                                        double max_step = 0.5);

Mat3 look_rotation(const Vec3& center, const Vec3& target);  // OpenCV axes, world z up

}  // namespace isplat::synth
