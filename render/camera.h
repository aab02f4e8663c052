// Cameras for the ray casters: orthographic or perspective, orbiting the centre of a bounding box,
// framed so that the box's bounding sphere fills the image at zoom 1.
//
// Orientation follows VTK's conventions: at azimuth 0 and elevation 0 the camera looks along -z with
// +y up; azimuth rotates the camera about the up axis, elevation about the camera's right axis
// (degrees). Pixel (0, 0) is the top-left corner; rays go through pixel centres.
#pragma once

#include <cmath>
#include <cstdint>

namespace gtn {

enum class Projection { kOrthographic, kPerspective };

struct CameraOptions {
  int width = 256, height = 256;
  Projection projection = Projection::kOrthographic;
  double azimuth = 30.0;    // degrees
  double elevation = 20.0;  // degrees
  double zoom = 1.0;        // > 1 magnifies
};

// A ray o + t d with |d| = 1, so that t measures distance. For the orthographic camera every ray
// starts on one plane behind the scene, so equal t means equal depth.
struct Ray {
  double o[3], d[3];
};

class Camera {
 public:
  Camera() = default;
  Camera(const double bbox_min[3], const double bbox_max[3], const CameraOptions& options);

  int width() const { return options_.width; }
  int height() const { return options_.height; }
  const CameraOptions& options() const { return options_; }
  Ray ray(int px, int py) const;
  // Continuous pixel coordinates of a point (x right, y down); false if behind a perspective eye.
  // Inline: the streaming renderer projects the four corners of every tetrahedron that arrives.
  bool project(const double p[3], double* x, double* y) const {
    if (options_.projection == Projection::kOrthographic) {
      *x = screen_x_[0] * p[0] + screen_x_[1] * p[1] + screen_x_[2] * p[2] + screen_x_[3];
      *y = screen_y_[0] * p[0] + screen_y_[1] * p[1] + screen_y_[2] * p[2] + screen_y_[3];
      return std::isfinite(*x) && std::isfinite(*y);
    }
    return projectPerspective(p, x, y);
  }
  // Radius of the framed bounding sphere.
  double radius() const { return radius_; }

  // The view in vtkCamera's terms, so that another renderer can reproduce it exactly: position,
  // focal point (the box centre) and view up; the orthographic parallel scale (half the image height
  // in world units) or the perspective view angle (vertical, degrees).
  const double* position() const { return eye_; }
  const double* focalPoint() const { return centre_; }
  const double* viewUp() const { return up_; }
  double parallelScale() const { return half_h_; }
  double viewAngleDeg() const;

 private:
  CameraOptions options_;
  double centre_[3] = {0, 0, 0};
  double radius_ = 1;
  double forward_[3] = {0, 0, -1}, right_[3] = {1, 0, 0}, up_[3] = {0, 1, 0};
  double eye_[3] = {0, 0, 0};       // perspective eye, or the orthographic rays' plane centre
  double half_w_ = 1, half_h_ = 1;  // orthographic: world units; perspective: tangents
  // Orthographic: pixel x = screen_x_ . (p, 1), y = screen_y_ . (p, 1). Perspective: the same before
  // the division by depth, relative to the eye and without the offset (screen_x_[3], screen_y_[3]
  // are then the image centre).
  double screen_x_[4] = {0, 0, 0, 0}, screen_y_[4] = {0, 0, 0, 0};
  bool projectPerspective(const double p[3], double* x, double* y) const;
};

}  // namespace gtn
