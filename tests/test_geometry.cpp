// Geometry: projection round trips, pose converters on hand-computed cases, Hypersim tilt-shift RQ,
// image/intrinsics resizing, and byte-mask dilation.
#include <catch2/catch.hpp>

#include <torch/torch.h>
#include <Eigen/Dense>
#include <opencv2/core.hpp>

#include "geometry/camera.h"
#include "geometry/camera_torch.h"
#include "geometry/convert.h"
#include "geometry/image_ops.h"
#include "geometry/pixel_mask.h"

using namespace isplat;

TEST_CASE("geometry: project after backproject is the identity", "[geometry]") {
  Intrinsics K{500.0, 480.0, 320.5, 240.25, 640, 480, 1.5};
  for (double u : {0.5, 100.0, 639.5})
    for (double v : {0.5, 240.0, 479.5})
      for (double z : {0.1, 2.0, 75.0}) {
        const Eigen::Vector3d X = K.backproject(u, v, z);
        CHECK(X.z() == Approx(z));
        const Eigen::Vector2d uv = K.project(X);
        CHECK(uv.x() == Approx(u).margin(1e-9));
        CHECK(uv.y() == Approx(v).margin(1e-9));
      }
  View view{K, make_pose(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(),
                         Eigen::Vector3d(0.5, -1.0, 2.0))};
  const Eigen::Vector3d Xw = view.backproject(123.0, 45.0, 3.5);
  Eigen::Vector2d uv;
  double z = 0;
  REQUIRE(view.project(Xw, uv, z));
  CHECK(uv.x() == Approx(123.0));
  CHECK(uv.y() == Approx(45.0));
  CHECK(z == Approx(3.5));
}

TEST_CASE("geometry: batched torch projection matches Eigen and round-trips", "[geometry]") {
  Intrinsics K{300.0, 310.0, 128.0, 96.0, 256, 192};
  auto Kt = make_K(K.fx, K.fy, K.cx, K.cy, torch::kFloat64);
  auto uv = torch::rand({2, 50, 2}, torch::kFloat64) * 200.0;
  auto z = torch::rand({2, 50}, torch::kFloat64) * 10.0 + 0.5;
  auto X = backproject_points(uv, z, Kt.expand({2, 3, 3}));
  CHECK(torch::allclose(project_points(X, Kt), uv, 1e-9, 1e-9));
  const Eigen::Vector3d Xe =
      K.backproject(uv[1][7][0].item<double>(), uv[1][7][1].item<double>(), z[1][7].item<double>());
  CHECK(X[1][7][0].item<double>() == Approx(Xe.x()));
  CHECK(X[1][7][1].item<double>() == Approx(Xe.y()));

  auto T = torch::eye(4, torch::kFloat64);
  T.narrow(0, 0, 3).narrow(1, 0, 3).copy_(
      torch::tensor({0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0}, torch::kFloat64).reshape({3, 3}));
  T.narrow(0, 0, 3).select(1, 3).copy_(torch::tensor({1.0, 2.0, 3.0}, torch::kFloat64));
  auto p = torch::tensor({{1.0, 0.0, 0.0}}, torch::kFloat64);
  CHECK(torch::allclose(transform_points(T, p), torch::tensor({{1.0, 3.0, 3.0}}, torch::kFloat64)));
  CHECK(torch::allclose(transform_points(invert_poses(T), transform_points(T, p)), p));

  auto centers = pixel_centers(2, 3);
  CHECK(centers[1][2][0].item<float>() == 2.5f);
  CHECK(centers[1][2][1].item<float>() == 1.5f);
}

TEST_CASE("geometry: COLMAP qvec/tvec is world-to-camera", "[geometry]") {
  // 90 degrees about z: q = (cos 45, 0, 0, sin 45); R = [[0,-1,0],[1,0,0],[0,0,1]].
  const double h = std::sqrt(0.5);
  Pose T = pose_from_colmap(Eigen::Vector4d(h, 0, 0, h), Eigen::Vector3d(1, 2, 3));
  const Eigen::Vector3d Xc = transform_point(T, Eigen::Vector3d(1, 0, 0));
  CHECK(Xc.x() == Approx(1.0));
  CHECK(Xc.y() == Approx(3.0));
  CHECK(Xc.z() == Approx(3.0));
  // Unnormalized quaternions are normalized; the inverse conversion returns the same pose.
  Pose T2 = pose_from_colmap(Eigen::Vector4d(2 * h, 0, 0, 2 * h), Eigen::Vector3d(1, 2, 3));
  CHECK((T2 - T).norm() < 1e-12);
  Eigen::Vector4d q;
  Eigen::Vector3d t;
  pose_to_colmap(T, q, t);
  CHECK((q - Eigen::Vector4d(h, 0, 0, h)).norm() < 1e-12);
  CHECK_THROWS_WITH(pose_from_colmap(Eigen::Vector4d(0, 0, 0, 0), Eigen::Vector3d::Zero()),
                    Catch::Contains("zero or non-finite norm"));
}

TEST_CASE("geometry: OpenGL c2w flips y and z", "[geometry]") {
  // A GL camera at (0, 0, 5) with identity rotation looks down -z at the origin.
  Eigen::Matrix4d c2w = Eigen::Matrix4d::Identity();
  c2w(2, 3) = 5.0;
  Pose T = pose_from_opengl_c2w(c2w);
  const Eigen::Vector3d o = transform_point(T, Eigen::Vector3d(0, 0, 0));
  CHECK(o.isApprox(Eigen::Vector3d(0, 0, 5)));
  const Eigen::Vector3d p = transform_point(T, Eigen::Vector3d(1, 1, 0));  // GL (1, 1, -5) -> CV (1, -1, 5)
  CHECK(p.isApprox(Eigen::Vector3d(1, -1, 5)));
  CHECK((opengl_c2w_from_pose(T) - c2w).norm() < 1e-12);
}

TEST_CASE("geometry: RQ decomposition", "[geometry]") {
  Eigen::Matrix3d A;
  A << 3, 1, 2, -1, 4, 0.5, 0.2, 0.3, 2;
  Eigen::Matrix3d R, Q;
  rq_decompose(A, R, Q);
  CHECK((R * Q - A).norm() < 1e-12);
  CHECK(std::abs(R(1, 0)) + std::abs(R(2, 0)) + std::abs(R(2, 1)) < 1e-12);
  CHECK(R(0, 0) > 0);
  CHECK(R(1, 1) > 0);
  CHECK(R(2, 2) > 0);
  CHECK((Q * Q.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(Q.determinant() == Approx(1.0));
}

TEST_CASE("geometry: Hypersim standard camera gives the 60 degree pinhole", "[geometry][hypersim]") {
  Eigen::Matrix3d M;
  M << 0.5773502886169104, 0, 0, 0, 0.4330127164626828, 0, 0, 0, -1;
  auto cam = hypersim_camera(M, 1024, 768);
  CHECK_FALSE(cam.tilt_shift);
  CHECK(cam.intr.fx == Approx(512.0 / 0.5773502886169104));
  CHECK(cam.intr.fy == Approx(384.0 / 0.4330127164626828));
  CHECK(cam.intr.cx == Approx(512.0));
  CHECK(cam.intr.cy == Approx(384.0));
  CHECK(cam.intr.skew == Approx(0.0).margin(1e-9));
  CHECK((cam.R_eff - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(hypersim_planar_factor(cam, 512.0, 384.0) == Approx(1.0));
}

TEST_CASE("geometry: Hypersim tilt-shift rays from K and R match M_cam_from_uv to 1e-9", "[geometry][hypersim]") {
  // A camera with shifted and tilted image plane (non-zero M20, M21 and shift terms).
  Eigen::Matrix3d M;
  M << 0.5773502886169104, 0.0, 0.021, 0.0, 0.4330127164626828, -0.035, 0.06, -0.08, -1.0;
  const int W = 1024, H = 768;
  auto cam = hypersim_camera(M, W, H);
  CHECK(cam.tilt_shift);
  CHECK((cam.R_eff - Eigen::Matrix3d::Identity()).norm() > 1e-3);  // the tilt is really folded into R
  const Eigen::Matrix3d F = Eigen::Vector3d(1, -1, -1).asDiagonal();
  double worst = 0;
  for (double x : {0.5, 100.25, 511.5, 1023.5})
    for (double y : {0.5, 383.5, 600.0, 767.5}) {
      const Eigen::Vector3d from_M = (F * cam.ray_gl(x, y)).normalized();  // OpenCV camera frame
      const Eigen::Vector3d from_K = (cam.R_eff.transpose() * cam.intr.ray(x, y)).normalized();
      worst = std::max(worst, (from_M - from_K).norm());
    }
  CHECK(worst < 1e-9);

  // A world point seen through the folded pose lands where the Hypersim ray model says, with planar depth
  // equal to distance x planar factor.
  const Eigen::Matrix3d R_wc = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  const Eigen::Vector3d pos_asset(120.0, -40.0, 55.0);
  const double mpau = 0.0254;
  View view{cam.intr, pose_from_hypersim(R_wc, pos_asset, mpau, cam)};
  const Eigen::Vector3d center = pos_asset * mpau;
  const double x = 300.5, y = 200.5, dist = 3.7;
  const Eigen::Vector3d dir_world = R_wc * cam.ray_gl(x, y).normalized();
  const Eigen::Vector3d Xw = center + dist * dir_world;
  Eigen::Vector2d uv;
  double z = 0;
  REQUIRE(view.project(Xw, uv, z));
  CHECK(uv.x() == Approx(x).margin(1e-9));
  CHECK(uv.y() == Approx(y).margin(1e-9));
  CHECK(z == Approx(dist * hypersim_planar_factor(cam, x, y)).epsilon(1e-12));
}

TEST_CASE("geometry: resizing and cropping keep projections consistent", "[geometry]") {
  Intrinsics K{400.0, 400.0, 320.0, 240.0, 640, 480};
  const Eigen::Vector3d X(0.3, -0.2, 2.5);
  const Eigen::Vector2d uv = K.project(X);
  const Intrinsics half = K.resized(320, 240);
  CHECK(half.project(X).isApprox(uv * 0.5));
  const Intrinsics c = K.cropped(100, 50, 200, 200);
  CHECK(c.project(X).isApprox(uv - Eigen::Vector2d(100, 50)));

  // fit_view: centre crop to 4:3 from 16:9, then shrink; the crop box and K follow.
  cv::Mat image(360, 640, CV_32FC3, cv::Scalar(0.2, 0.4, 0.6));
  cv::Mat depth(360, 640, CV_32FC1, cv::Scalar(2.0));
  Intrinsics k2{500.0, 500.0, 320.0, 180.0, 640, 360};
  fit_view(image, &depth, k2, 160, 120);
  CHECK(image.cols == 160);
  CHECK(depth.rows == 120);
  CHECK(k2.width == 160);
  CHECK(k2.cx == Approx(80.0));
  CHECK(k2.fx == Approx(500.0 * 160.0 / 480.0));
  CHECK(depth.at<float>(60, 80) == 2.0f);
  const auto box = center_crop_box(640, 360, 4.0 / 3.0);
  CHECK(box.width == 480);
  CHECK(box.x0 == 80);

  // Torch form agrees with the Eigen form.
  auto img = torch::rand({3, 48, 64});
  auto [small, Ks] = resize_with_K(img, make_K(400, 400, 32, 24, torch::kFloat64), 24, 32);
  CHECK(small.size(1) == 24);
  CHECK(Ks[0][0].item<double>() == Approx(200.0));
  CHECK(Ks[1][2].item<double>() == Approx(12.0));
  auto [cropped, Kc] = crop_with_K(img, make_K(400, 400, 32, 24, torch::kFloat64), 4, 2, 16, 10);
  CHECK(cropped.size(2) == 16);
  CHECK(Kc[0][2].item<double>() == Approx(28.0));
  CHECK_THROWS_WITH(crop_with_K(img, make_K(1, 1, 0, 0), 60, 0, 16, 10), Catch::Contains("outside"));
}

TEST_CASE("mirror_K: a mirrored point projects to the mirrored pixel, skew included, batched or not", "[geometry]") {
  auto K = make_K(300, 280, 20.5, 14, torch::kFloat64);
  K[0][1] = 7.0;  // skew, which mirroring negates
  const int64_t W = 48;
  const auto points = torch::tensor({{0.3, -0.2, 2.0}, {-1.1, 0.4, 3.5}, {0.0, 0.0, 1.0}}, torch::kFloat64);
  const auto mirrored = points * torch::tensor({-1.0, 1.0, 1.0}, torch::kFloat64);
  const auto uv = project_points(points, K), uv_m = project_points(mirrored, mirror_K(K, W));
  CHECK(torch::allclose(uv_m.select(1, 0), W - uv.select(1, 0)));
  CHECK(torch::allclose(uv_m.select(1, 1), uv.select(1, 1)));
  CHECK(torch::equal(mirror_K(mirror_K(K, W), W), K));  // an involution
  const auto batched = mirror_K(torch::stack({K, K}), W);
  CHECK(torch::equal(batched[1], mirror_K(K, W)));
  CHECK(K[0][2].item<double>() == 20.5);  // the input is not modified
  CHECK(K[0][1].item<double>() == 7.0);
  CHECK_THROWS_WITH(mirror_K(torch::eye(2), W), Catch::Contains("mirror_K"));
}

TEST_CASE("pixel mask: square dilation grows a pixel to a (2r+1)^2 block, clipped at the border", "[geometry]") {
  const int64_t H = 6, W = 7;
  std::vector<uint8_t> m(H * W, 0);
  m[2 * W + 3] = 1;  // one pixel inside
  m[0] = 1;          // one in the corner
  const auto d = dilate_square(m, H, W, 1);
  int64_t set = 0;
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      const bool near_inner = std::abs(i - 2) <= 1 && std::abs(j - 3) <= 1, near_corner = i <= 1 && j <= 1;
      CHECK(d[i * W + j] == (near_inner || near_corner ? 1 : 0));
      set += d[i * W + j];
    }
  CHECK(set == 9 + 4);
  CHECK(dilate_square(m, H, W, 0) == m);
  CHECK(dilate_square(m, H, W, 10) == std::vector<uint8_t>(H * W, 1));
  CHECK_THROWS_WITH(dilate_square(m, H, W + 1, 1), Catch::Contains("dilate_square"));
}
