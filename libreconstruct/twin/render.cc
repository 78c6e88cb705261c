// The renderer of a simulated net through a camera (see render.h).

#include "libreconstruct/twin/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "calibration/camera.h"

namespace netlab::recon {
namespace {

// Half the largest extent of a pixel across a thread (its diagonal), px.
constexpr double kMaxFootprint = 0.5 * std::numbers::sqrt2;

// ---------------------------------------------------------------------------------------------
// Undistorted rays.

// A camera's undistorted normalised coordinates (X/Z, Y/Z) on a grid of nodes every kStep px,
// node (i, j) at pixel (i kStep - 1/2, j kStep - 1/2) (so pixel corners fall on nodes), filled
// lazily by Newton's method (calib::UndistortPoint). Between nodes, bilinear interpolation: the
// undistortion field is smooth, its error is ~kStep^2 / 8 times its second derivative (for the
// paper's 16 mm lens, k1 = -0.08: < 1e-3 px).
class RayGrid {
 public:
  static constexpr int kShift = 3, kStep = 1 << kShift;

  explicit RayGrid(const calib::CameraIntrinsics& intrinsics)
      : intrinsics_(intrinsics),
        nodes_x_((intrinsics.width >> kShift) + 2),
        nodes_y_((intrinsics.height >> kShift) + 2),
        nodes_(static_cast<size_t>(nodes_x_) * nodes_y_),
        done_(nodes_.size(), 0) {
    // Extent of the image in normalised coordinates, from its border (for culling threads).
    min_ = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    max_ = -min_;
    auto extend = [&](int u, int v) {
      const Eigen::Vector2d& n = Corner(u, v);
      if (!n.allFinite()) return;
      min_ = min_.cwiseMin(n);
      max_ = max_.cwiseMax(n);
    };
    for (int u = 0; u <= intrinsics.width; u += kStep) {
      extend(u, 0);
      extend(u, intrinsics.height);
    }
    for (int v = 0; v <= intrinsics.height; v += kStep) {
      extend(0, v);
      extend(intrinsics.width, v);
    }
    // The radius up to which the radial distortion is monotonic: beyond it, points fold back
    // into the image, so thread points there are not drawn.
    const double* k = intrinsics.distortion.data();
    double previous = 0.0;
    max_radius_ = 10.0;
    for (double r = 0.005; r <= 10.0; r += 0.005) {
      const double r2 = r * r, r4 = r2 * r2, r6 = r4 * r2;
      const double rd =
          r * (1 + k[0] * r2 + k[1] * r4 + k[4] * r6) / (1 + k[5] * r2 + k[6] * r4 + k[7] * r6);
      if (!(rd > previous)) {
        max_radius_ = r - 0.005;
        break;
      }
      previous = rd;
    }
  }

  bool Matches(const calib::CameraIntrinsics& k) const {
    const calib::CameraIntrinsics& m = intrinsics_;
    return m.width == k.width && m.height == k.height && m.fx == k.fx && m.fy == k.fy &&
           m.cx == k.cx && m.cy == k.cy && m.distortion == k.distortion && m.rational == k.rational;
  }

  // Normalised coordinates of the ray through pixel corner (u - 1/2, v - 1/2),
  // 0 <= u <= width, 0 <= v <= height.
  Eigen::Vector2d Corner(int u, int v) {
    const int i = u >> kShift, j = v >> kShift;
    const double fu = (u & (kStep - 1)) * (1.0 / kStep), fv = (v & (kStep - 1)) * (1.0 / kStep);
    const Eigen::Vector2d& a = Node(i, j);
    if (fu == 0.0 && fv == 0.0) return a;
    const Eigen::Vector2d& b = Node(i + 1, j);
    const Eigen::Vector2d& c = Node(i, j + 1);
    const Eigen::Vector2d& d = Node(i + 1, j + 1);
    return (1 - fv) * ((1 - fu) * a + fu * b) + fv * ((1 - fu) * c + fu * d);
  }

  // Rays (x, y, 1) through the corners (u, v), u0 <= u < u0 + cols, v0 <= v < v0 + rows, row
  // by row into `rays` (cols * rows).
  void Corners(int u0, int v0, int cols, int rows, Eigen::Vector3d* rays) {
    const int i0 = u0 >> kShift, i1 = ((u0 + cols - 1) >> kShift) + 1;
    column_.resize(i1 - i0 + 1);
    for (int r = 0; r < rows; ++r) {
      const int v = v0 + r, j = v >> kShift;
      const double fv = (v & (kStep - 1)) * (1.0 / kStep);
      // Interpolated along v at each node column, then along u.
      for (int i = i0; i <= i1; ++i)
        column_[i - i0] = fv == 0.0 ? Node(i, j) : (1 - fv) * Node(i, j) + fv * Node(i, j + 1);
      for (int c = 0; c < cols; ++c) {
        const int u = u0 + c, i = (u >> kShift) - i0;
        const double fu = (u & (kStep - 1)) * (1.0 / kStep);
        const Eigen::Vector2d n = (1 - fu) * column_[i] + fu * column_[i + 1];
        rays[static_cast<size_t>(r) * cols + c] = Eigen::Vector3d(n.x(), n.y(), 1.0);
      }
    }
  }

  const Eigen::Vector2d& min() const { return min_; }
  const Eigen::Vector2d& max() const { return max_; }
  double max_radius() const { return max_radius_; }

 private:
  const Eigen::Vector2d& Node(int i, int j) {
    const size_t index = static_cast<size_t>(j) * nodes_x_ + i;
    if (!done_[index]) {
      nodes_[index] =
          calib::UndistortPoint(intrinsics_, Eigen::Vector2d(i * kStep - 0.5, j * kStep - 0.5));
      done_[index] = 1;
    }
    return nodes_[index];
  }

  calib::CameraIntrinsics intrinsics_;
  int nodes_x_, nodes_y_;
  std::vector<Eigen::Vector2d> nodes_;
  std::vector<uint8_t> done_;
  std::vector<Eigen::Vector2d> column_;  // scratch of Corners
  Eigen::Vector2d min_, max_;
  double max_radius_ = 10.0;
};

// The ray grid of `intrinsics`: each thread keeps those of the last few cameras it rendered.
RayGrid& RaysOf(const calib::CameraIntrinsics& intrinsics) {
  thread_local std::array<std::unique_ptr<RayGrid>, 8> cache;
  thread_local size_t next = 0;
  for (auto& grid : cache)
    if (grid && grid->Matches(intrinsics)) return *grid;
  auto& slot = cache[next++ % cache.size()];
  slot = std::make_unique<RayGrid>(intrinsics);
  return *slot;
}

// ---------------------------------------------------------------------------------------------
// The canvas: the image being rendered, in 32 x 32 tiles allocated when first touched.

// One 32 x 32 tile, field by field. Only colour and solid_alpha are set when the tile is first
// touched; the other fields are valid where their guards say (less memory to write: most of a
// render's time is memory traffic).
struct Tile {
  static constexpr int kShift = 5, kSize = 1 << kShift, kMask = kSize - 1;
  static constexpr int kPixels = kSize * kSize;
  static int Index(int x, int y) { return ((y & kMask) << kShift) | (x & kMask); }

  std::array<cv::Vec3f, kPixels> colour;   // the composite so far (linear BGR)
  std::array<float, kPixels> solid_alpha;  // fraction of the pixel covered by solids
  // Where solid_alpha > 0: depth of the nearest solid sample (camera z, m).
  std::array<float, kPixels> solid_depth;
  // Where 0 < solid_alpha < 1: the solids' colour premultiplied by solid_alpha.
  std::array<cv::Vec3f, kPixels> solid;
  // Where thread_stamp is the stamp of the polyline being drawn: its distance (px), coverage
  // and depth (camera z, m) at its nearest point.
  std::array<uint32_t, kPixels> thread_stamp;
  std::array<float, kPixels> thread_distance;
  std::array<float, kPixels> thread_alpha;
  std::array<float, kPixels> thread_depth;
  std::array<float, kPixels> thread_shade;  // with lamps: the thread's shading there
  int tx = 0, ty = 0;                       // where the tile is in the image (tiles)
};

// The image being rendered, in tiles allocated when first touched (a pool kept between renders).
class Canvas {
 public:
  // An untouched canvas of the given size: every pixel shows `background`.
  void Reset(int width, int height, const Colour& background,
             const cv::Mat* background_image = nullptr) {
    background_image_ = background_image;
    width_ = width;
    height_ = height;
    tiles_x_ = (width + Tile::kMask) >> Tile::kShift;
    tiles_y_ = (height + Tile::kMask) >> Tile::kShift;
    slots_.assign(static_cast<size_t>(tiles_x_) * tiles_y_, -1);
    used_ = 0;
    background_ = background;
  }

  // Tile (tx, ty), initialised to the background when first touched.
  Tile& At(int tx, int ty) {
    int& slot = slots_[static_cast<size_t>(ty) * tiles_x_ + tx];
    if (slot < 0) {
      if (used_ == pool_.size()) {
        pool_.push_back(std::make_unique<Tile>());
        pool_.back()->thread_stamp.fill(0);  // stamps start at 1
      }
      slot = static_cast<int>(used_++);
      Tile& tile = *pool_[slot];
      tile.tx = tx;
      tile.ty = ty;
      if (background_image_ == nullptr) {
        tile.colour.fill(background_);
      } else {
        const int x0 = tx << Tile::kShift, y0 = ty << Tile::kShift;
        for (int y = y0; y < std::min(height_, y0 + Tile::kSize); ++y) {
          const cv::Vec3f* row = background_image_->ptr<cv::Vec3f>(y);
          for (int x = x0; x < std::min(width_, x0 + Tile::kSize); ++x)
            tile.colour[Tile::Index(x, y)] = row[x];
        }
      }
      tile.solid_alpha.fill(0.0f);
    }
    return *pool_[slot];
  }
  Tile& TileOf(int x, int y) { return At(x >> Tile::kShift, y >> Tile::kShift); }
  // Tile (tx, ty) if it was touched, else null.
  const Tile* Find(int tx, int ty) const {
    const int slot = slots_[static_cast<size_t>(ty) * tiles_x_ + tx];
    return slot < 0 ? nullptr : pool_[slot].get();
  }
  // A stamp no pixel holds yet (for the next polyline).
  uint32_t NewStamp() {
    if (++stamp_ == 0) {  // wrapped: forget every stamp
      for (auto& tile : pool_) tile->thread_stamp.fill(0);
      stamp_ = 1;
    }
    return stamp_;
  }

  int width() const { return width_; }
  int height() const { return height_; }
  int tiles_x() const { return tiles_x_; }
  int tiles_y() const { return tiles_y_; }
  const Colour& background() const { return background_; }
  // The background at pixel (x, y).
  Colour BackgroundAt(int x, int y) const {
    return background_image_ == nullptr ? background_ : background_image_->at<cv::Vec3f>(y, x);
  }
  const cv::Mat* background_image() const { return background_image_; }

 private:
  int width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<int> slots_;  // tile -> index in pool_, or -1
  std::vector<std::unique_ptr<Tile>> pool_;
  size_t used_ = 0;
  uint32_t stamp_ = 0;
  Colour background_;
  const cv::Mat* background_image_ = nullptr;
};

// ---------------------------------------------------------------------------------------------
// Solids.

struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive
  bool empty() const { return x1 < x0 || y1 < y0; }
  bool Contains(int x, int y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
};

// The pixels whose centres lie within `margin` px of the bounding box of `pixels`, clipped to
// the image.
PixelRect RectAround(const std::vector<Eigen::Vector2d>& pixels, double margin, int width,
                     int height) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Eigen::Vector2d& p : pixels) {
    if (!p.allFinite()) return {0, 0, width - 1, height - 1};
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  PixelRect r;
  if (!(lo.x() - margin < width && lo.y() - margin < height && hi.x() + margin > -1 &&
        hi.y() + margin > -1))
    return r;  // empty
  r.x0 = std::max(0, static_cast<int>(std::ceil(lo.x() - margin)));
  r.y0 = std::max(0, static_cast<int>(std::ceil(lo.y() - margin)));
  r.x1 = std::min(width - 1, static_cast<int>(std::floor(hi.x() + margin)));
  r.y1 = std::min(height - 1, static_cast<int>(std::floor(hi.y() + margin)));
  return r;
}

class Lighting;

// A ball or a box in the camera frame, with its shading.
struct Solid {
  bool is_ball = true;
  PixelRect rect;
  bool supersample_all = true;  // every pixel of the rect, not only where corners disagree
  // Ball.
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // camera frame, m
  double radius = 0.0;
  Colour colour{0, 0, 0};
  // Box.
  Eigen::Matrix3d box_from_cam = Eigen::Matrix3d::Identity();
  Eigen::Vector3d camera_in_box = Eigen::Vector3d::Zero();  // the projection centre, box frame
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
  std::array<Colour, 6> face_colours{};  // +x, -x, +y, -y, +z, -z, shaded

  // The nearest intersection of the ray t (x, y, 1) (camera frame) with t > 0: its depth t and
  // face (0 for a ball). False on a miss.
  bool Intersect(const Eigen::Vector3d& ray, double* depth, int* face) const {
    if (is_ball) {
      // |t ray - c|^2 = r^2, the smaller root.
      const double a = ray.squaredNorm(), b = ray.dot(center);
      const double disc = b * b - a * (center.squaredNorm() - radius * radius);
      if (!(disc >= 0.0)) return false;
      const double t = (b - std::sqrt(disc)) / a;
      if (!(t > 0.0)) return false;
      *depth = t;
      *face = 0;
      return true;
    }
    // Slabs in the box frame (Kay and Kajiya 1986).
    const Eigen::Vector3d d = box_from_cam * ray;
    double t_near = -std::numeric_limits<double>::infinity();
    double t_far = std::numeric_limits<double>::infinity();
    int near_face = -1;
    for (int axis = 0; axis < 3; ++axis) {
      const double o = camera_in_box[axis], h = half_extents[axis];
      if (d[axis] == 0.0) {
        if (o < -h || o > h) return false;
        continue;
      }
      const double inv = 1.0 / d[axis];
      double t0 = (-h - o) * inv, t1 = (h - o) * inv;
      // Entering through the -axis face when the ray goes +axis.
      int entry_face = 2 * axis + 1;
      if (t0 > t1) {
        std::swap(t0, t1);
        entry_face = 2 * axis;
      }
      if (t0 > t_near) {
        t_near = t0;
        near_face = entry_face;
      }
      t_far = std::min(t_far, t1);
    }
    if (!(t_near <= t_far) || !(t_near > 0.0) || near_face < 0) return false;
    *depth = t_near;
    *face = near_face;
    return true;
  }

  // The shade of the point of `face` at `depth` along `ray`: by the lamps of `lighting` when
  // there is one, else by the directional light.
  Colour Shade(const Eigen::Vector3d& ray, double depth, int face, const Eigen::Vector3d& light,
               double ambient, const Lighting* lighting) const;
  Colour ShadeDirectional(const Eigen::Vector3d& ray, double depth, int face,
                          const Eigen::Vector3d& light, double ambient) const {
    if (!is_ball) return face_colours[face];
    const Eigen::Vector3d normal = (depth * ray - center) / radius;
    const double lambert = ambient + (1.0 - ambient) * std::max(0.0, normal.dot(light));
    return colour * static_cast<float>(lambert);
  }
};

// The lamps of a scene in the camera frame, and the boxes that can hide them (see
// SceneRenderOptions::lamps).
class Lighting {
 public:
  Lighting(const calib::Camera& camera, const SceneRenderOptions& options,
           const std::vector<Solid>& solids)
      : ambient_(options.ambient), glossy_(options.glossy), shininess_(options.shininess) {
    for (const Lamp& lamp : options.lamps)
      lamps_.push_back({camera.cam_from_world * lamp.position, lamp.power});
    for (const Solid& solid : solids)
      if (!solid.is_ball) boxes_.push_back(&solid);
  }

  // A surface point p (camera frame) of unit normal n on `self` (a box: it cannot shadow a
  // face turned to the lamp; null for a ball): its colour; `glossy` adds the lamps' highlights.
  Colour Surface(const Colour& colour, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                 bool glossy, const Solid* self) const {
    const Eigen::Vector3d view = -p.normalized();
    double diffuse = ambient_, specular = 0.0;
    for (const auto& [position, power] : lamps_) {
      const Eigen::Vector3d d = position - p;
      const double r2 = d.squaredNorm();
      const Eigen::Vector3d l = d / std::sqrt(r2);
      const double cosine = n.dot(l);
      if (!(cosine > 0.0) || Hidden(p, position, self)) continue;
      diffuse += power * cosine / r2;
      if (glossy && glossy_ > 0.0) {
        const double nh = std::max(0.0, n.dot((l + view).normalized()));
        specular += power * std::pow(nh, shininess_) / r2;
      }
    }
    const float s = static_cast<float>(glossy_ * specular);
    return colour * static_cast<float>(diffuse) + Colour(s, s, s);
  }

  // The shading of a thread of unit tangent t at p (camera frame): a Lambertian cylinder.
  float Thread(const Eigen::Vector3d& p, const Eigen::Vector3d& t) const {
    double shade = ambient_;
    for (const auto& [position, power] : lamps_) {
      const Eigen::Vector3d d = position - p;
      const double r2 = d.squaredNorm();
      const double along = t.dot(d) / std::sqrt(r2);
      if (Hidden(p, position)) continue;
      shade += power * std::sqrt(std::max(0.0, 1.0 - along * along)) / r2;
    }
    return static_cast<float>(shade);
  }

  // Does the segment from p to the lamp at q (camera frame) pass through a box other than
  // `self`?
  bool Hidden(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
              const Solid* self = nullptr) const {
    for (const Solid* box : boxes_) {
      if (box == self) continue;
      const Eigen::Vector3d a = box->box_from_cam * p + box->camera_in_box;
      const Eigen::Vector3d d = box->box_from_cam * (q - p);
      double t0 = 0.0, t1 = 1.0;
      bool miss = false;
      for (int i = 0; i < 3 && !miss; ++i) {
        const double h = box->half_extents[i];
        if (std::abs(d[i]) < 1e-15) {
          miss = std::abs(a[i]) > h;
          continue;
        }
        double ta = (-h - a[i]) / d[i], tb = (h - a[i]) / d[i];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        miss = t0 > t1;
      }
      if (!miss) return true;
    }
    return false;
  }

 private:
  std::vector<std::pair<Eigen::Vector3d, double>> lamps_;  // camera frame, power
  std::vector<const Solid*> boxes_;
  double ambient_, glossy_, shininess_;
};

Colour Solid::Shade(const Eigen::Vector3d& ray, double depth, int face,
                    const Eigen::Vector3d& light, double ambient, const Lighting* lighting) const {
  if (lighting == nullptr) return ShadeDirectional(ray, depth, face, light, ambient);
  const Eigen::Vector3d p = depth * ray;
  if (is_ball) return lighting->Surface(colour, p, (p - center) / radius, false, nullptr);
  const int axis = face / 2;
  const Eigen::Vector3d normal = (face % 2 ? -1.0 : 1.0) * box_from_cam.row(axis).transpose();
  return lighting->Surface(colour, p, normal, true, this);
}

Colour Lambert(const Colour& colour, const Eigen::Vector3d& normal, const Eigen::Vector3d& light,
               double ambient) {
  return colour * static_cast<float>(ambient + (1.0 - ambient) * std::max(0.0, normal.dot(light)));
}

// Balls and boxes of the scene in the camera frame with their pixel rectangles; those behind
// the near plane or outside the image are left out. `light` is in the camera frame.
std::vector<Solid> CameraSolids(const calib::Camera& camera, const Scene& scene,
                                const SceneRenderOptions& options, const Eigen::Vector3d& light) {
  const calib::CameraIntrinsics& k = camera.intrinsics;
  const Eigen::Matrix3d cam_from_world = camera.cam_from_world.RotationMatrix();
  std::vector<Solid> solids;
  std::vector<Eigen::Vector2d> outline;
  // Small solids (< this many px across) are supersampled everywhere: they can hide between the
  // four corners of a pixel.
  constexpr int kSmallPx = 8;

  for (const Ball& ball : scene.balls) {
    Solid s;
    s.is_ball = true;
    s.center = camera.cam_from_world * ball.center;
    s.radius = ball.radius;
    s.colour = ball.colour;
    const double distance = s.center.norm();
    if (!(ball.radius > 0.0) || distance <= ball.radius) continue;  // nothing, or around us
    if (s.center.z() + ball.radius < options.near_plane) continue;
    if (s.center.z() - ball.radius < options.near_plane) {
      s.rect = {0, 0, k.width - 1, k.height - 1};  // straddles the near plane
    } else {
      // The silhouette: the circle where rays from the centre touch the sphere, sampled.
      const double r2 = ball.radius * ball.radius / (distance * distance);
      const Eigen::Vector3d axis = s.center / distance;
      const Eigen::Vector3d circle_center = s.center * (1.0 - r2);
      const double circle_radius = ball.radius * std::sqrt(1.0 - r2);
      const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
      constexpr int kOutline = 24;
      outline.clear();
      for (int i = 0; i < kOutline; ++i) {
        const double a = 2.0 * std::numbers::pi * i / kOutline;
        outline.push_back(calib::Project(
            k, circle_center + circle_radius * (std::cos(a) * e1 + std::sin(a) * e2)));
      }
      // Chords of the sampled outline lie inside the true one by up to 1 - cos(pi / 24) of its
      // radius (< 1 %): a margin of that, one pixel and a half.
      const double radius_px = ball.radius * k.fx / s.center.z();
      s.rect = RectAround(outline, 1.5 + 0.01 * radius_px, k.width, k.height);
    }
    if (s.rect.empty()) continue;
    solids.push_back(s);
  }

  for (const Box& box : scene.boxes) {
    if (!(box.half_extents.minCoeff() > 0.0)) continue;
    Solid s;
    s.is_ball = false;
    const Eigen::Matrix3d cam_from_box = cam_from_world * box.orientation.toRotationMatrix();
    const Eigen::Vector3d center = camera.cam_from_world * box.center;
    s.box_from_cam = cam_from_box.transpose();
    s.camera_in_box = -(s.box_from_cam * center);
    s.half_extents = box.half_extents;
    s.colour = box.colour;
    if ((s.camera_in_box.cwiseAbs() - s.half_extents).maxCoeff() < 0.0) continue;  // inside
    for (int axis = 0; axis < 3; ++axis) {
      s.face_colours[2 * axis] =
          Lambert(box.colour, cam_from_box.col(axis), light, options.ambient);
      s.face_colours[2 * axis + 1] =
          Lambert(box.colour, -cam_from_box.col(axis), light, options.ambient);
    }
    // The outline: the twelve edges, each sampled (distortion bends them).
    constexpr int kEdgeSamples = 8;
    outline.clear();
    bool behind = false;
    double min_z = std::numeric_limits<double>::infinity();
    for (int edge_axis = 0; edge_axis < 3; ++edge_axis)
      for (int corner = 0; corner < 4; ++corner) {
        Eigen::Vector3d a;
        const int other1 = (edge_axis + 1) % 3, other2 = (edge_axis + 2) % 3;
        a[edge_axis] = 0.0;
        a[other1] = (corner & 1) ? box.half_extents[other1] : -box.half_extents[other1];
        a[other2] = (corner & 2) ? box.half_extents[other2] : -box.half_extents[other2];
        for (int i = 0; i <= kEdgeSamples; ++i) {
          a[edge_axis] = box.half_extents[edge_axis] * (2.0 * i / kEdgeSamples - 1.0);
          const Eigen::Vector3d p = center + cam_from_box * a;
          min_z = std::min(min_z, p.z());
          if (p.z() < options.near_plane) behind = true;
          outline.push_back(calib::Project(k, p));
        }
      }
    if (min_z == std::numeric_limits<double>::infinity()) continue;
    if (behind) {
      const bool all_behind =
          std::all_of(outline.begin(), outline.end(), [](const auto& p) { return !p.allFinite(); });
      if (all_behind) continue;
      s.rect = {0, 0, k.width - 1, k.height - 1};
    } else {
      s.rect = RectAround(outline, 1.5, k.width, k.height);
    }
    if (s.rect.empty()) continue;
    s.supersample_all = s.rect.x1 - s.rect.x0 < kSmallPx || s.rect.y1 - s.rect.y0 < kSmallPx;
    solids.push_back(s);
  }
  return solids;
}

// Ray casts the solids into the canvas tile by tile: for each tile, the solids whose rectangles
// overlap it; for each pixel in one of those rectangles, one centre sample where its four
// corners see the same face of the same solid, else supersample^2 samples (rays interpolated
// between the pixel's corner rays).
class SolidCaster {
 public:
  SolidCaster(const std::vector<Solid>& solids, const SceneRenderOptions& options,
              const Eigen::Vector3d& light, const Lighting* lighting, RayGrid& rays, Canvas& canvas)
      : lighting_(lighting),
        solids_(solids),
        options_(options),
        light_(light),
        rays_(rays),
        canvas_(canvas),
        supersample_(options.solid_supersample),
        inv_samples_(1.0f / static_cast<float>(supersample_ * supersample_)) {}

  // Casts the solids into every tile that one of their rectangles overlaps.
  void Draw() {
    if (solids_.empty()) return;
    const std::vector<std::pair<int, int>> pairs = TileSolidPairs();
    for (size_t begin = 0; begin < pairs.size();) {
      // The solids of one tile.
      const int tile_index = pairs[begin].first;
      list_.clear();
      size_t end = begin;
      for (; end < pairs.size() && pairs[end].first == tile_index; ++end)
        list_.push_back(pairs[end].second);
      begin = end;
      DrawTile(tile_index % canvas_.tiles_x(), tile_index / canvas_.tiles_x());
    }
  }

 private:
  // (tile, solid) pairs, grouped by tile.
  std::vector<std::pair<int, int>> TileSolidPairs() const {
    std::vector<std::pair<int, int>> pairs;
    for (int i = 0; i < static_cast<int>(solids_.size()); ++i) {
      const PixelRect& r = solids_[i].rect;
      for (int ty = r.y0 >> Tile::kShift; ty <= r.y1 >> Tile::kShift; ++ty)
        for (int tx = r.x0 >> Tile::kShift; tx <= r.x1 >> Tile::kShift; ++tx)
          pairs.emplace_back(ty * canvas_.tiles_x() + tx, i);
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  }

  // The part of tile (tx, ty) inside the rectangles of the tile's solids (list_).
  PixelRect RegionOf(int tx, int ty) const {
    const int tile_x0 = tx << Tile::kShift, tile_y0 = ty << Tile::kShift;
    PixelRect region{std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), -1, -1};
    for (int i : list_) {
      const PixelRect& r = solids_[i].rect;
      region.x0 = std::min(region.x0, std::max(r.x0, tile_x0));
      region.y0 = std::min(region.y0, std::max(r.y0, tile_y0));
      region.x1 = std::max(region.x1, std::min(r.x1, tile_x0 + Tile::kMask));
      region.y1 = std::max(region.y1, std::min(r.y1, tile_y0 + Tile::kMask));
    }
    region.x1 = std::min(region.x1, canvas_.width() - 1);
    region.y1 = std::min(region.y1, canvas_.height() - 1);
    return region;
  }

  // What a ray sees among the tile's solids: its depth and id (solid * 8 + face), or -1 and
  // infinity; false on a miss.
  bool Nearest(const Eigen::Vector3d& ray, double* depth, int* id) const {
    *id = -1;
    *depth = std::numeric_limits<double>::infinity();
    for (int i : list_) {
      double t;
      int face;
      if (solids_[i].Intersect(ray, &t, &face) && t < *depth) {
        *depth = t;
        *id = i * 8 + face;
      }
    }
    return *id >= 0;
  }

  // Casts the tile's solids (list_) into tile (tx, ty): the whole tile at once where it lies
  // inside one box face, else pixel by pixel from the rays through the pixels' corners.
  void DrawTile(int tx, int ty) {
    region_ = RegionOf(tx, ty);
    if (region_.empty()) return;
    // The corner grid of the region: (width + 1) x (height + 1) corners.
    cw_ = region_.x1 - region_.x0 + 2;
    ch_ = region_.y1 - region_.y0 + 2;
    if (FillInsideFace(tx, ty)) return;

    // What the corner rays see: solid * 8 + face, or -1.
    corner_rays_.resize(static_cast<size_t>(cw_) * ch_);
    corner_ids_.resize(corner_rays_.size());
    corner_depths_.resize(corner_rays_.size());
    rays_.Corners(region_.x0, region_.y0, cw_, ch_, corner_rays_.data());
    for (size_t c = 0; c < corner_rays_.size(); ++c)
      Nearest(corner_rays_[c], &corner_depths_[c], &corner_ids_[c]);

    // Each pixel in a solid's rectangle: one sample where its corners agree, else supersampled.
    Tile& tile = canvas_.At(tx, ty);
    for (int y = region_.y0; y <= region_.y1; ++y)
      for (int x = region_.x0; x <= region_.x1; ++x) {
        bool inside = false, supersample = false;
        for (int i : list_) {
          if (!solids_[i].rect.Contains(x, y)) continue;
          inside = true;
          supersample = supersample || solids_[i].supersample_all;
        }
        if (!inside) continue;
        const size_t c = static_cast<size_t>(y - region_.y0) * cw_ + (x - region_.x0);
        const int id = corner_ids_[c];
        if (!supersample && id == corner_ids_[c + 1] && id == corner_ids_[c + cw_] &&
            id == corner_ids_[c + cw_ + 1])
          ShadeOneFace(x, y, c, tile);
        else
          Supersample(x, y, c, tile);
      }
  }

  // A tile inside one face of a box: the face's image is convex in undistorted coordinates,
  // so when every corner on the tile's border sees it, the whole tile does. Its colour is the
  // face's; 1 / depth is affine in undistorted coordinates, nearly so in pixels: bilinear
  // from the tile's corners. False (nothing drawn) unless the tile is such a tile.
  bool FillInsideFace(int tx, int ty) {
    const Solid& first = solids_[list_[0]];
    const int tile_x0 = tx << Tile::kShift, tile_y0 = ty << Tile::kShift;
    const int tile_x1 = std::min(tile_x0 + Tile::kMask, canvas_.width() - 1);
    const int tile_y1 = std::min(tile_y0 + Tile::kMask, canvas_.height() - 1);
    if (!(lighting_ == nullptr && list_.size() == 1 && !first.is_ball && !first.supersample_all &&
          region_.x0 == tile_x0 && region_.y0 == tile_y0 && region_.x1 == tile_x1 &&
          region_.y1 == tile_y1))
      return false;
    // The rays through the corners on the border: top, bottom, left, right.
    border_rays_.resize(2 * (cw_ + ch_));
    Eigen::Vector3d* top = border_rays_.data();
    Eigen::Vector3d* bottom = top + cw_;
    Eigen::Vector3d* left = bottom + cw_;
    Eigen::Vector3d* right = left + ch_;
    rays_.Corners(region_.x0, region_.y0, cw_, 1, top);
    rays_.Corners(region_.x0, region_.y0 + ch_ - 1, cw_, 1, bottom);
    rays_.Corners(region_.x0, region_.y0, 1, ch_, left);
    rays_.Corners(region_.x0 + cw_ - 1, region_.y0, 1, ch_, right);
    // Do they all see one face? The depths at the tile's four corners on the way.
    int face = -1;
    bool uniform = true;
    double depth = 1.0, corner_depth[4] = {1.0, 1.0, 1.0, 1.0};
    for (size_t c = 0; c < border_rays_.size() && uniform; ++c) {
      int hit = -1;
      uniform = first.Intersect(border_rays_[c], &depth, &hit) && (face < 0 || hit == face);
      face = hit;
      if (c == 0) corner_depth[0] = depth;
      if (c == static_cast<size_t>(cw_) - 1) corner_depth[1] = depth;
      if (c == static_cast<size_t>(cw_)) corner_depth[2] = depth;
      if (c == 2 * static_cast<size_t>(cw_) - 1) corner_depth[3] = depth;
    }
    if (!uniform) return false;
    // The face's colour everywhere, 1 / depth bilinear.
    Tile& tile = canvas_.At(tx, ty);
    const Colour colour = first.face_colours[face];
    const double w = cw_ - 1, h = ch_ - 1;
    for (int y = region_.y0; y <= region_.y1; ++y) {
      const double fy = (y - region_.y0 + 0.5) / h;
      const double inv_left = (1 - fy) / corner_depth[0] + fy / corner_depth[2];
      const double inv_right = (1 - fy) / corner_depth[1] + fy / corner_depth[3];
      for (int x = region_.x0; x <= region_.x1; ++x) {
        const double fx = (x - region_.x0 + 0.5) / w;
        const int i = Tile::Index(x, y);
        tile.colour[i] = colour;
        tile.solid_alpha[i] = 1.0f;
        tile.solid_depth[i] = static_cast<float>(1.0 / ((1 - fx) * inv_left + fx * inv_right));
      }
    }
    return true;
  }

  // Pixel (x, y), whose four corners (from corner c of the grid) see the same face or nothing:
  // a box face is flat-shaded and its depth nearly affine across the pixel; a ball's shading
  // is taken at the centre.
  void ShadeOneFace(int x, int y, size_t c, Tile& tile) const {
    const int id = corner_ids_[c];
    if (id < 0) return;  // no solid here
    const Solid& solid = solids_[id / 8];
    double depth = 0.25 * (corner_depths_[c] + corner_depths_[c + 1] + corner_depths_[c + cw_] +
                           corner_depths_[c + cw_ + 1]);
    int hit = id;
    const Eigen::Vector3d ray = 0.25 * (corner_rays_[c] + corner_rays_[c + 1] +
                                        corner_rays_[c + cw_] + corner_rays_[c + cw_ + 1]);
    if (solid.is_ball && !Nearest(ray, &depth, &hit)) return;
    const int i = Tile::Index(x, y);
    tile.colour[i] =
        solids_[hit / 8].Shade(ray, depth, hit % 8, light_, options_.ambient, lighting_);
    tile.solid_alpha[i] = 1.0f;
    tile.solid_depth[i] = static_cast<float>(depth);
  }

  // Pixel (x, y) from s x s samples at ((a + 1/2) / s, (b + 1/2) / s) of the pixel, their rays
  // bilinear between its corner rays (from corner c of the grid); the solids' coverage blends
  // them over the background.
  void Supersample(int x, int y, size_t c, Tile& tile) const {
    const int s = supersample_;
    const Eigen::Vector3d& r00 = corner_rays_[c];
    const Eigen::Vector3d& r10 = corner_rays_[c + 1];
    const Eigen::Vector3d& r01 = corner_rays_[c + cw_];
    const Eigen::Vector3d& r11 = corner_rays_[c + cw_ + 1];
    cv::Vec3f sum(0, 0, 0);
    int hits = 0;
    double min_depth = std::numeric_limits<double>::infinity();
    for (int b = 0; b < s; ++b) {
      const double fy = (b + 0.5) / s;
      const Eigen::Vector3d left = (1 - fy) * r00 + fy * r01;
      const Eigen::Vector3d right = (1 - fy) * r10 + fy * r11;
      for (int a = 0; a < s; ++a) {
        const double fx = (a + 0.5) / s;
        const Eigen::Vector3d ray = (1 - fx) * left + fx * right;
        double depth;
        int hit;
        if (!Nearest(ray, &depth, &hit)) continue;
        sum += solids_[hit / 8].Shade(ray, depth, hit % 8, light_, options_.ambient, lighting_);
        ++hits;
        min_depth = std::min(min_depth, depth);
      }
    }
    if (hits == 0) return;
    const int i = Tile::Index(x, y);
    tile.solid[i] = sum * inv_samples_;
    tile.solid_alpha[i] = static_cast<float>(hits) * inv_samples_;
    tile.solid_depth[i] = static_cast<float>(min_depth);
    tile.colour[i] = tile.solid[i] + canvas_.BackgroundAt(x, y) * (1.0f - tile.solid_alpha[i]);
  }

  const Lighting* lighting_;  // null: the directional light
  const std::vector<Solid>& solids_;
  const SceneRenderOptions& options_;
  const Eigen::Vector3d& light_;  // camera frame
  RayGrid& rays_;
  Canvas& canvas_;
  const int supersample_;    // samples per side of a supersampled pixel
  const float inv_samples_;  // 1 / supersample_^2
  // The tile being drawn: its solids (indices in solids_), the part of it they cover, and that
  // part's corner grid (cw_ x ch_ corners, row by row).
  std::vector<int> list_;
  PixelRect region_;
  int cw_ = 0, ch_ = 0;
  std::vector<Eigen::Vector3d> corner_rays_;
  std::vector<int> corner_ids_;
  std::vector<double> corner_depths_;
  std::vector<Eigen::Vector3d> border_rays_;  // FillInsideFace's
};

// Ray casts the solids into the canvas (see SolidCaster).
void DrawSolids(const std::vector<Solid>& solids, const SceneRenderOptions& options,
                const Eigen::Vector3d& light, const Lighting* lighting, RayGrid& rays,
                Canvas& canvas) {
  SolidCaster(solids, options, light, lighting, rays, canvas).Draw();
}

// ---------------------------------------------------------------------------------------------
// Threads.

// A point of a thread in the image.
struct ThreadVertex {
  Eigen::Vector3d in_cam;      // camera frame, m
  Eigen::Vector2d pixel;       // px
  Eigen::Vector2d normalised;  // X/Z, Y/Z
  double width = 0.0;          // px
  bool valid = false;          // where the camera model is one-to-one
  float shade = 1.0f;          // with lamps: the thread's shading here
};

// The fraction of a pixel covered by a straight strip: the pixel's footprint across the strip.
// A point (x, y) of the unit square, uniformly distributed, lies at s = x n_x + y n_y across a
// strip of unit normal n: s is the sum of two uniform variables of widths a = |n_x| and
// b = |n_y|, so its density is a trapezoid (flat on |s| <= (a - b) / 2, ramps of width b) and
// the strip [d - w/2, d + w/2] covers G(d + w/2) - G(d - w/2) of the pixel, G the trapezoid's
// cumulative distribution. Along the image axes (b = 0) this is the overlap of the strip with
// [-1/2, 1/2].
class PixelFootprint {
 public:
  // `direction` along the strip, px (need not be unit length); `square` false: the interval
  // [-1/2, 1/2] whatever the direction.
  PixelFootprint(const Eigen::Vector2d& direction, bool square) {
    const double length = direction.norm();
    if (square && length > 0.0) {
      a_ = std::max(std::abs(direction.x()), std::abs(direction.y())) / length;
      b_ = std::min(std::abs(direction.x()), std::abs(direction.y())) / length;
    }
    if (b_ < 1e-6) b_ = 0.0;
    half_ = 0.5 * (a_ + b_);
    flat_ = 0.5 * (a_ - b_);
    inv_2ab_ = b_ > 0.0 ? 0.5 / (a_ * b_) : 0.0;
  }
  // Coverage of the pixel by a strip of width w whose centreline passes d px from its centre.
  double Coverage(double d, double w) const { return Cdf(d + 0.5 * w) - Cdf(d - 0.5 * w); }

 private:
  double Cdf(double s) const {
    if (s <= -half_) return 0.0;
    if (s >= half_) return 1.0;
    if (s < -flat_) return (s + half_) * (s + half_) * inv_2ab_;
    if (s > flat_) return 1.0 - (half_ - s) * (half_ - s) * inv_2ab_;
    return 0.5 + s / a_;
  }
  double a_ = 1.0, b_ = 0.0, half_ = 0.5, flat_ = 0.5, inv_2ab_ = 0.0;
};

class ThreadDrawer {
 public:
  ThreadDrawer(const calib::Camera& camera, const SceneRenderOptions& options, RayGrid& rays,
               Canvas& canvas, cv::Mat* depth, const Lighting* lighting)
      : depth_(depth),
        lighting_(lighting),
        camera_(camera),
        params_(camera.intrinsics.ToParameters()),
        options_(options),
        rays_(rays),
        canvas_(canvas),
        max_radius2_(rays.max_radius() * rays.max_radius()) {}

  // Draws one polyline over the canvas (see render.h).
  void Draw(const ThreadPolyline& thread) {
    radius_ = thread.radius;
    stamp_ = canvas_.NewStamp();
    touched_.clear();
    for (size_t i = 0; i + 1 < thread.points.size(); ++i) {
      Eigen::Vector3d a = camera_.cam_from_world * thread.points[i];
      Eigen::Vector3d b = camera_.cam_from_world * thread.points[i + 1];
      // Clip at the near plane.
      const double near = options_.near_plane;
      if (a.z() < near && b.z() < near) continue;
      if (a.z() < near) a = b + (a - b) * ((b.z() - near) / (b.z() - a.z()));
      if (b.z() < near) b = a + (b - a) * ((a.z() - near) / (a.z() - b.z()));
      if (lighting_ != nullptr) tangent_ = (b - a).normalized();
      const ThreadVertex va = Vertex(a), vb = Vertex(b);
      // Split into pieces of about max_piece_px first, then bisect where that was not enough.
      int n = 1;
      if (va.valid && vb.valid) {
        const double chord = (vb.pixel - va.pixel).norm();
        n = static_cast<int>(std::clamp(std::ceil(chord / options_.max_piece_px), 1.0, 4096.0));
      }
      ThreadVertex previous = va;
      for (int j = 1; j <= n; ++j) {
        const ThreadVertex next = j == n ? vb : Vertex(a + (b - a) * (double(j) / n));
        Subdivide(previous, next, 0);
        previous = next;
      }
    }
    // Composite: over the canvas, or behind the solids nearer than the thread.
    for (const auto& [tile, i] : touched_) {
      const float alpha = tile->thread_alpha[i];
      if (alpha <= 0.0f) continue;
      const Colour colour =
          lighting_ == nullptr ? thread.colour : thread.colour * tile->thread_shade[i];
      cv::Vec3f& pixel = tile->colour[i];
      const float solid_alpha = tile->solid_alpha[i];
      if (solid_alpha > 0.0f && tile->solid_depth[i] < tile->thread_depth[i]) {
        // pixel = solid + (1 - solid_alpha) behind; the thread goes over `behind`.
        if (solid_alpha >= 1.0f) continue;
        pixel += alpha * ((1.0f - solid_alpha) * colour - (pixel - tile->solid[i]));
      } else {
        pixel += alpha * (colour - pixel);
      }
      if (depth_ != nullptr) {
        float& d = depth_->at<float>((tile->ty << Tile::kShift) | (i >> Tile::kShift),
                                     (tile->tx << Tile::kShift) | (i & Tile::kMask));
        d = std::min(d, tile->thread_depth[i]);
      }
    }
  }

 private:
  ThreadVertex Vertex(const Eigen::Vector3d& in_cam) const {
    ThreadVertex v;
    v.in_cam = in_cam;
    v.normalised = in_cam.head<2>() / in_cam.z();
    v.valid = v.normalised.squaredNorm() <= max_radius2_;
    double xd, yd;
    calib::Distort(params_.data() + 4, v.normalised.x(), v.normalised.y(), &xd, &yd);
    v.pixel = Eigen::Vector2d(params_[0] * xd + params_[2], params_[1] * yd + params_[3]);
    v.width = 2.0 * radius_ * params_[0] / in_cam.z();
    if (lighting_ != nullptr) v.shade = lighting_->Thread(in_cam, tangent_);
    return v;
  }

  // Draws the piece a-b, bisected until its image is at most max_piece_px long; pieces entirely
  // beside the image are dropped (tested on normalised coordinates, where the piece is straight).
  void Subdivide(const ThreadVertex& a, const ThreadVertex& b, int level) {
    const double margin = (0.5 * std::max(a.width, b.width) + 4.0) / params_[0];
    const Eigen::Vector2d lo = rays_.min().array() - margin, hi = rays_.max().array() + margin;
    if ((a.normalised.x() < lo.x() && b.normalised.x() < lo.x()) ||
        (a.normalised.y() < lo.y() && b.normalised.y() < lo.y()) ||
        (a.normalised.x() > hi.x() && b.normalised.x() > hi.x()) ||
        (a.normalised.y() > hi.y() && b.normalised.y() > hi.y()))
      return;
    constexpr int kMaxLevel = 24;
    const bool valid = a.valid && b.valid;
    // A piece shorter than one in the undistorted image that reaches where the camera model
    // folds back: not drawn.
    if (!valid && (b.normalised - a.normalised).norm() * params_[0] < options_.max_piece_px) return;
    if ((valid && (b.pixel - a.pixel).norm() <= options_.max_piece_px) || level >= kMaxLevel) {
      if (valid) Rasterise(a, b);
      return;
    }
    const ThreadVertex mid = Vertex(0.5 * (a.in_cam + b.in_cam));
    Subdivide(a, mid, level + 1);
    Subdivide(mid, b, level + 1);
  }

  // Records, for each pixel near the piece, its distance to the piece when nearer than to the
  // polyline's other pieces so far.
  void Rasterise(const ThreadVertex& a, const ThreadVertex& b) {
    const double extent = 0.5 * std::max(a.width, b.width) + kMaxFootprint;
    const int x0 =
        std::max(0, static_cast<int>(std::ceil(std::min(a.pixel.x(), b.pixel.x()) - extent)));
    const int x1 =
        std::min(canvas_.width() - 1,
                 static_cast<int>(std::floor(std::max(a.pixel.x(), b.pixel.x()) + extent)));
    const int y0 =
        std::max(0, static_cast<int>(std::ceil(std::min(a.pixel.y(), b.pixel.y()) - extent)));
    const int y1 =
        std::min(canvas_.height() - 1,
                 static_cast<int>(std::floor(std::max(a.pixel.y(), b.pixel.y()) + extent)));
    if (x1 < x0 || y1 < y0) return;
    const Eigen::Vector2d e = b.pixel - a.pixel;
    const PixelFootprint footprint(e, options_.square_pixel_footprint);
    const double length2 = e.squaredNorm();
    const double inv_length2 = length2 > 0.0 ? 1.0 / length2 : 0.0;
    const double za = a.in_cam.z(), zb = b.in_cam.z();
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d q = Eigen::Vector2d(x, y) - a.pixel;
        const double t = std::clamp(q.dot(e) * inv_length2, 0.0, 1.0);
        const double d = (q - t * e).norm();
        const double w = a.width + t * (b.width - a.width);
        if (d >= 0.5 * w + kMaxFootprint) continue;  // not covered
        Tile& tile = canvas_.TileOf(x, y);
        const int i = Tile::Index(x, y);
        if (tile.thread_stamp[i] != stamp_) {
          tile.thread_stamp[i] = stamp_;
          touched_.push_back({&tile, i});
        } else if (!(d < tile.thread_distance[i])) {
          continue;
        }
        tile.thread_distance[i] = static_cast<float>(d);
        tile.thread_alpha[i] = static_cast<float>(footprint.Coverage(d, w));
        tile.thread_depth[i] = static_cast<float>(za + t * (zb - za));
        if (lighting_ != nullptr)
          tile.thread_shade[i] = static_cast<float>(a.shade + t * (b.shade - a.shade));
      }
  }

  cv::Mat* depth_;            // null, or where to keep the least depth per pixel
  const Lighting* lighting_;  // null: threads unshaded
  Eigen::Vector3d tangent_ = Eigen::Vector3d::UnitX();  // of the piece being drawn, with lamps
  const calib::Camera& camera_;
  const std::array<double, calib::kNumIntrinsics> params_;
  const SceneRenderOptions& options_;
  RayGrid& rays_;
  Canvas& canvas_;
  const double max_radius2_;
  double radius_ = 0.0;
  uint32_t stamp_ = 0;
  std::vector<std::pair<Tile*, int>> touched_;  // pixels near the polyline being drawn
};

// Throws std::invalid_argument naming the first non-finite or negative value of the scene.
void CheckScene(const Scene& scene) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("RenderScene: " + what); };
  for (size_t i = 0; i < scene.threads.size(); ++i) {
    const ThreadPolyline& t = scene.threads[i];
    if (!(t.radius >= 0.0) || !std::isfinite(t.radius))
      fail("thread " + std::to_string(i) + " has radius " + std::to_string(t.radius));
    for (size_t j = 0; j < t.points.size(); ++j)
      if (!t.points[j].allFinite())
        fail("thread " + std::to_string(i) + " point " + std::to_string(j) + " is not finite");
  }
  for (size_t i = 0; i < scene.balls.size(); ++i) {
    const Ball& b = scene.balls[i];
    if (!b.center.allFinite() || !(b.radius >= 0.0) || !std::isfinite(b.radius))
      fail("ball " + std::to_string(i) + " has a non-finite centre or an invalid radius");
  }
  for (size_t i = 0; i < scene.boxes.size(); ++i) {
    const Box& b = scene.boxes[i];
    if (!b.center.allFinite() || !b.orientation.coeffs().allFinite() ||
        !(b.half_extents.minCoeff() >= 0.0) || !b.half_extents.allFinite())
      fail("box " + std::to_string(i) + " has a non-finite pose or invalid half extents");
  }
}

}  // namespace

bool SceneRenderOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!light_direction.allFinite() || !(light_direction.norm() > 0.0))
    os << "light_direction must be a finite non-zero vector";
  else if (!(ambient >= 0.0 && ambient <= 1.0))
    os << "ambient " << ambient << " must be in [0, 1]";
  else if (!(max_piece_px > 0.0) || !std::isfinite(max_piece_px))
    os << "max_piece_px " << max_piece_px << " must be positive";
  else if (solid_supersample < 1 || solid_supersample > 64)
    os << "solid_supersample " << solid_supersample << " must be in [1, 64]";
  else if (!(near_plane > 0.0) || !std::isfinite(near_plane))
    os << "near_plane " << near_plane << " must be positive";
  else if (!(glossy >= 0.0) || !std::isfinite(glossy))
    os << "glossy " << glossy << " must be >= 0";
  else if (!(shininess > 0.0) || !std::isfinite(shininess))
    os << "shininess " << shininess << " must be positive";
  for (const Lamp& lamp : lamps)
    if (os.str().empty() &&
        (!lamp.position.allFinite() || !(lamp.power >= 0.0) || !std::isfinite(lamp.power)))
      os << "a lamp needs a finite position and a power >= 0";
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

void RenderScene(const calib::Camera& camera, const Scene& scene, const SceneRenderOptions& options,
                 float weight, cv::Mat* accumulator) {
  RenderScene(camera, scene, options, weight, accumulator, nullptr);
}

void RenderScene(const calib::Camera& camera, const Scene& scene, const SceneRenderOptions& options,
                 float weight, cv::Mat* accumulator, cv::Mat* depth) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("RenderScene: " + error);
  const calib::CameraIntrinsics& k = camera.intrinsics;
  if (!k.IsValid(&error))
    throw std::invalid_argument("RenderScene: camera " + camera.name + ": " + error);
  if (accumulator == nullptr) throw std::invalid_argument("RenderScene: null accumulator");
  if (accumulator->empty()) {
    accumulator->create(k.height, k.width, CV_32FC3);
    accumulator->setTo(cv::Scalar::all(0));
  }
  if (accumulator->type() != CV_32FC3 || accumulator->cols != k.width ||
      accumulator->rows != k.height) {
    std::ostringstream os;
    os << "RenderScene: the accumulator must be CV_32FC3 of " << k.width << "x" << k.height
       << " (camera " << camera.name << "), not type " << accumulator->type() << " of "
       << accumulator->cols << "x" << accumulator->rows;
    throw std::invalid_argument(os.str());
  }
  const cv::Mat* background_image = options.background_image;
  if (background_image != nullptr &&
      (background_image->type() != CV_32FC3 || background_image->cols != k.width ||
       background_image->rows != k.height))
    throw std::invalid_argument(
        "RenderScene: the background image must be CV_32FC3 of the "
        "camera's size (camera " +
        camera.name + ")");
  if (depth != nullptr) {
    if (depth->empty()) {
      depth->create(k.height, k.width, CV_32F);
      depth->setTo(cv::Scalar::all(std::numeric_limits<float>::infinity()));
    }
    if (depth->type() != CV_32F || depth->cols != k.width || depth->rows != k.height)
      throw std::invalid_argument(
          "RenderScene: the depth map must be CV_32F of the camera's "
          "size (camera " +
          camera.name + ")");
  }
  CheckScene(scene);

  thread_local Canvas canvas;
  canvas.Reset(k.width, k.height, scene.background, background_image);
  RayGrid& rays = RaysOf(k);
  const Eigen::Vector3d light =
      camera.cam_from_world.rotation * options.light_direction.normalized();

  // Solids first: the depth buffer the threads are tested against.
  const std::vector<Solid> solids = CameraSolids(camera, scene, options, light);
  std::unique_ptr<Lighting> lighting;
  if (!options.lamps.empty()) lighting = std::make_unique<Lighting>(camera, options, solids);
  DrawSolids(solids, options, light, lighting.get(), rays, canvas);

  // Threads far to near (by the mean depth of their points).
  std::vector<std::pair<double, int>> order;
  for (int i = 0; i < static_cast<int>(scene.threads.size()); ++i) {
    const ThreadPolyline& t = scene.threads[i];
    if (t.points.size() < 2 || !(t.radius > 0.0)) continue;
    double z = 0.0;
    for (const Eigen::Vector3d& p : t.points) z += (camera.cam_from_world * p).z();
    order.emplace_back(-z / t.points.size(), i);
  }
  std::sort(order.begin(), order.end());
  ThreadDrawer drawer(camera, options, rays, canvas, depth, lighting.get());
  for (const auto& [negative_depth, i] : order) drawer.Draw(scene.threads[i]);

  // Accumulate: the touched tiles, and the background elsewhere, as flat float spans of one
  // tile row (3 x 32 floats) so that the loops vectorise.
  const bool black = scene.background == Colour(0, 0, 0) && background_image == nullptr;
  std::array<float, 3 * Tile::kSize> background;
  for (int x = 0; x < Tile::kSize; ++x)
    for (int c = 0; c < 3; ++c) background[3 * x + c] = scene.background[c] * weight;
  for (int ty = 0; ty < canvas.tiles_y(); ++ty)
    for (int tx = 0; tx < canvas.tiles_x(); ++tx) {
      const Tile* tile = canvas.Find(tx, ty);
      if (tile == nullptr && black) continue;
      const int x0 = tx << Tile::kShift, y0 = ty << Tile::kShift;
      const int n = 3 * (std::min(k.width, x0 + Tile::kSize) - x0);
      const int y1 = std::min(k.height, y0 + Tile::kSize);
      for (int y = y0; y < y1; ++y) {
        float* out = accumulator->ptr<float>(y) + 3 * x0;
        if (tile == nullptr && background_image != nullptr) {
          const float* in = background_image->ptr<float>(y) + 3 * x0;
          for (int i = 0; i < n; ++i) out[i] += weight * in[i];
          continue;
        }
        if (tile == nullptr) {
          for (int i = 0; i < n; ++i) out[i] += background[i];
          continue;
        }
        const float* in = &tile->colour[(y & Tile::kMask) << Tile::kShift][0];
        for (int i = 0; i < n; ++i) out[i] += weight * in[i];
        if (depth != nullptr) {
          float* d = depth->ptr<float>(y) + x0;
          const int row = (y & Tile::kMask) << Tile::kShift;
          for (int i = 0; i < n / 3; ++i)
            if (tile->solid_alpha[row + i] > 0.0f)
              d[i] = std::min(d[i], tile->solid_depth[row + i]);
        }
      }
    }
}

cv::Mat RenderScene(const calib::Camera& camera, const Scene& scene,
                    const SceneRenderOptions& options) {
  cv::Mat image;
  RenderScene(camera, scene, options, 1.0f, &image);
  return image;
}

double SensorOptions::white() const { return std::ldexp(1.0, bit_depth) - 1.0; }

bool CameraResponse::IsIdentity() const {
  return white_balance == std::array<double, 3>{1.0, 1.0, 1.0} && gain == 1.0 && gamma == 1.0 &&
         prnu == 0.0 && dsnu == 0.0 && hot_pixels == 0.0;
}

bool CameraResponse::IsValid(std::string* error) const {
  std::ostringstream os;
  for (double w : white_balance)
    if (!(w > 0.0) || !std::isfinite(w)) os << "white_balance " << w << " must be > 0";
  if (!os.str().empty()) {
  } else if (!(gain > 0.0) || !std::isfinite(gain)) {
    os << "gain " << gain << " must be > 0";
  } else if (!(gamma > 0.0 && gamma <= 4.0)) {
    os << "gamma " << gamma << " must be in (0, 4]";
  } else if (!(prnu >= 0.0 && prnu <= 1.0)) {
    os << "prnu " << prnu << " must be in [0, 1]";
  } else if (!(dsnu >= 0.0 && dsnu <= 255.0)) {
    os << "dsnu " << dsnu << " must be in [0, 255]";
  } else if (!(hot_pixels >= 0.0 && hot_pixels <= 1.0)) {
    os << "hot_pixels " << hot_pixels << " must be in [0, 1]";
  }
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

bool SensorOptions::IsValid(std::string* error) const {
  std::ostringstream os;
  if (bit_depth != 8 && bit_depth != 10 && bit_depth != 12 && bit_depth != 16)
    os << "bit_depth " << bit_depth << " must be 8, 10, 12 or 16";
  else if (!(noise_sigma >= 0.0) || !std::isfinite(noise_sigma))
    os << "noise_sigma " << noise_sigma << " must be >= 0";
  else if (!(vignetting >= 0.0 && vignetting <= 1.0))
    os << "vignetting " << vignetting << " must be in [0, 1]";
  else if (!(black_level >= 0.0 && black_level < white()))
    os << "black_level " << black_level << " must be in [0, " << white() << ")";
  else if (std::string reason; !response.IsValid(&reason))
    os << "response: " << reason;
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

cv::Mat Expose(const cv::Mat& linear_bgr, const calib::CameraIntrinsics& intrinsics,
               const SensorOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("Expose: " + error);
  if (!intrinsics.IsValid(&error)) throw std::invalid_argument("Expose: camera: " + error);
  if (linear_bgr.type() != CV_32FC3 || linear_bgr.cols != intrinsics.width ||
      linear_bgr.rows != intrinsics.height) {
    std::ostringstream os;
    os << "Expose: the image must be CV_32FC3 of " << intrinsics.width << "x" << intrinsics.height
       << ", not type " << linear_bgr.type() << " of " << linear_bgr.cols << "x" << linear_bgr.rows;
    throw std::invalid_argument(os.str());
  }
  const int width = linear_bgr.cols, height = linear_bgr.rows;
  const float white = static_cast<float>(options.white());
  const float black = static_cast<float>(options.black_level);
  const float span = white - black;

  // Read noise in output units, one value per pixel.
  cv::Mat noise;
  if (options.noise_sigma > 0.0) {
    noise.create(height, width, CV_32F);
    cv::RNG rng(options.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, options.noise_sigma * span / 255.0);
  }
  // Vignetting: cos^4 theta = 1 / (1 + tan^2 theta)^2, tan^2 theta = x^2 + y^2 (normalised).
  std::vector<float> x2(width);
  for (int x = 0; x < width; ++x) {
    const double n = (x - intrinsics.cx) / intrinsics.fx;
    x2[x] = static_cast<float>(n * n);
  }
  const float v = static_cast<float>(options.vignetting);
  // The camera's response: its fixed patterns, drawn with its own seed (the same every frame).
  const CameraResponse& response = options.response;
  const bool respond = !response.IsIdentity();
  cv::Mat prnu, dsnu, hot;
  if (respond) {
    cv::RNG pattern(response.pattern_seed);
    if (response.prnu > 0.0) {
      prnu.create(height, width, CV_32F);
      pattern.fill(prnu, cv::RNG::NORMAL, 1.0, response.prnu);
    }
    if (response.dsnu > 0.0) {
      dsnu.create(height, width, CV_32F);
      pattern.fill(dsnu, cv::RNG::NORMAL, 0.0, response.dsnu * span / 255.0);
    }
    if (response.hot_pixels > 0.0) {
      hot.create(height, width, CV_32F);
      pattern.fill(hot, cv::RNG::UNIFORM, 0.0, 1.0);
    }
  }

  cv::Mat out(height, width, options.bit_depth == 8 ? CV_8U : CV_16U);
  std::vector<float> raw(width);
  for (int y = 0; y < height; ++y) {
    const cv::Vec3f* in = linear_bgr.ptr<cv::Vec3f>(y);
    const double ny = (y - intrinsics.cy) / intrinsics.fy;
    const float y2 = static_cast<float>(ny * ny);
    // The colour of the sites of this row (even and odd columns); -1: luminance.
    const int c0 = BayerColor(options.bayer, y, 0), c1 = BayerColor(options.bayer, y, 1);
    if (c0 < 0) {
      for (int x = 0; x < width; ++x)
        raw[x] = 0.0722f * in[x][0] + 0.7152f * in[x][1] + 0.2126f * in[x][2];
    } else {
      int x = 0;
      for (; x + 1 < width; x += 2) {
        raw[x] = in[x][c0];
        raw[x + 1] = in[x + 1][c1];
      }
      if (x < width) raw[x] = in[x][c0];
    }
    if (v > 0.0f) {
      for (int x = 0; x < width; ++x) {
        const float q = 1.0f + x2[x] + y2;
        raw[x] *= 1.0f - v * (1.0f - 1.0f / (q * q));
      }
    }
    // A non-finite value would round to anything: report where it is.
    int bad = 0;
    for (int x = 0; x < width; ++x) bad |= !(std::abs(raw[x]) <= std::numeric_limits<float>::max());
    if (bad)
      for (int x = 0; x < width; ++x)
        if (!std::isfinite(raw[x]))
          throw std::invalid_argument("Expose: the image has a non-finite value at (x " +
                                      std::to_string(x) + ", y " + std::to_string(y) + ")");
    if (respond) {
      // Site gains (a mono sensor takes the green one), pixel gains, the response curve.
      const float g0 = static_cast<float>(response.gain * response.white_balance[c0 < 0 ? 1 : c0]);
      const float g1 = static_cast<float>(response.gain * response.white_balance[c1 < 0 ? 1 : c1]);
      const float* p = prnu.empty() ? nullptr : prnu.ptr<float>(y);
      const float gamma = static_cast<float>(response.gamma);
      for (int x = 0; x < width; ++x) {
        float value = std::max(0.0f, raw[x] * ((x & 1) ? g1 : g0) * (p ? p[x] : 1.0f));
        if (gamma != 1.0f) value = std::pow(value, gamma);
        raw[x] = value;
      }
      if (!dsnu.empty()) {
        const float* o = dsnu.ptr<float>(y);
        for (int x = 0; x < width; ++x) raw[x] += o[x] / span;
      }
    }
    const float* n = noise.empty() ? nullptr : noise.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      // Rounded half up, clamped to [0, white].
      raw[x] = std::clamp(black + raw[x] * span + (n ? n[x] : 0.0f) + 0.5f, 0.0f, white + 0.5f);
    }
    if (!hot.empty()) {
      const float* h = hot.ptr<float>(y);
      const float fraction = static_cast<float>(response.hot_pixels);
      for (int x = 0; x < width; ++x)
        if (h[x] < fraction) raw[x] = white;
    }
    if (options.bit_depth == 8) {
      uint8_t* o = out.ptr<uint8_t>(y);
      for (int x = 0; x < width; ++x) o[x] = static_cast<uint8_t>(raw[x]);
    } else {
      uint16_t* o = out.ptr<uint16_t>(y);
      for (int x = 0; x < width; ++x) o[x] = static_cast<uint16_t>(raw[x]);
    }
  }
  return out;
}

}  // namespace netlab::recon
