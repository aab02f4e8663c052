#include "render/camera.h"

#include <algorithm>
#include <cmath>

namespace gtn {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kPerspectiveFovDeg = 30.0;  // vertical field of view, as VTK's default view angle

void normalize(double v[3]) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (n > 0)
    for (int i = 0; i < 3; ++i) v[i] /= n;
}
void cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}
double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
}  // namespace

Camera::Camera(const double bbox_min[3], const double bbox_max[3], const CameraOptions& options) : options_(options) {
  options_.width = std::max(1, options_.width);
  options_.height = std::max(1, options_.height);
  if (!(options_.zoom > 0)) options_.zoom = 1;
  double r2 = 0;
  for (int i = 0; i < 3; ++i) {
    centre_[i] = 0.5 * (bbox_min[i] + bbox_max[i]);
    const double h = 0.5 * (bbox_max[i] - bbox_min[i]);
    r2 += h * h;
  }
  radius_ = r2 > 0 ? std::sqrt(r2) : 1.0;
  const double az = options_.azimuth * kPi / 180.0, el = options_.elevation * kPi / 180.0;
  // Direction from the centre to the camera.
  const double to_eye[3] = {std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az)};
  for (int i = 0; i < 3; ++i) forward_[i] = -to_eye[i];
  // Up is +y rotated by the elevation, so that it stays perpendicular to the view direction.
  const double world_up[3] = {-std::sin(el) * std::sin(az), std::cos(el), -std::sin(el) * std::cos(az)};
  cross(forward_, world_up, right_);
  normalize(right_);
  cross(right_, forward_, up_);
  normalize(up_);
  const double aspect = static_cast<double>(options_.width) / options_.height;
  if (options_.projection == Projection::kOrthographic) {
    half_h_ = radius_ / options_.zoom;
    half_w_ = half_h_ * aspect;
    for (int i = 0; i < 3; ++i) eye_[i] = centre_[i] - forward_[i] * 2.0 * radius_;
  } else {
    const double half_fov = 0.5 * kPerspectiveFovDeg * kPi / 180.0;
    const double distance = radius_ / std::sin(half_fov);
    for (int i = 0; i < 3; ++i) eye_[i] = centre_[i] - forward_[i] * distance;
    half_h_ = std::tan(half_fov) / options_.zoom;
    half_w_ = half_h_ * aspect;
  }
  // x = (v . right / half_w + 1) W / 2 and y = (1 - v . up / half_h) H / 2, v = p - eye (divided by
  // the depth v . forward first, in perspective).
  const double kx = 0.5 * options_.width / half_w_, ky = -0.5 * options_.height / half_h_;
  for (int i = 0; i < 3; ++i) screen_x_[i] = kx * right_[i], screen_y_[i] = ky * up_[i];
  screen_x_[3] = 0.5 * options_.width, screen_y_[3] = 0.5 * options_.height;
  if (options_.projection == Projection::kOrthographic) {
    screen_x_[3] -= dot(screen_x_, eye_);
    screen_y_[3] -= dot(screen_y_, eye_);
  }
}

Ray Camera::ray(int px, int py) const {
  const double x = (2.0 * (px + 0.5) / options_.width - 1.0) * half_w_;
  const double y = (1.0 - 2.0 * (py + 0.5) / options_.height) * half_h_;
  Ray r;
  if (options_.projection == Projection::kOrthographic) {
    for (int i = 0; i < 3; ++i) {
      r.o[i] = eye_[i] + right_[i] * x + up_[i] * y;
      r.d[i] = forward_[i];
    }
  } else {
    for (int i = 0; i < 3; ++i) {
      r.o[i] = eye_[i];
      r.d[i] = forward_[i] + right_[i] * x + up_[i] * y;
    }
    normalize(r.d);
  }
  return r;
}

double Camera::viewAngleDeg() const {
  if (options_.projection == Projection::kOrthographic) return kPerspectiveFovDeg;
  return 2.0 * std::atan(half_h_) * 180.0 / kPi;
}

bool Camera::projectPerspective(const double p[3], double* x, double* y) const {
  const double v[3] = {p[0] - eye_[0], p[1] - eye_[1], p[2] - eye_[2]};
  const double depth = dot(v, forward_);
  if (!(depth > 0)) return false;
  *x = dot(v, screen_x_) / depth + screen_x_[3];
  *y = dot(v, screen_y_) / depth + screen_y_[3];
  return std::isfinite(*x) && std::isfinite(*y);
}

}  // namespace gtn
