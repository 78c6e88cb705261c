// The flight's acquisition effects on the twin's shots (see flight_effects.h).

#include "libreconstruct/twin/flight_effects.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <random>
#include <sstream>

#include "common/errors.h"
#include "common/yaml_util.h"

namespace netlab::recon {
namespace {

constexpr double kPi = std::numbers::pi;

// The time a PWM wave with on-fraction `duty` has been on from phase 0 to phase x (periods).
double OnPeriods(double x, double duty) {
  const double whole = std::floor(x);
  return whole * duty + std::min(x - whole, duty);
}

}  // namespace

double Flicker::Intensity(double t) const {
  if (!enabled()) return 1.0;
  if (duty <= 0.0) return 1.0 + depth * std::cos(2.0 * kPi * hz * t);
  const double on = 1.0 / (duty + (1.0 - duty) * (1.0 - depth));
  const double phase = hz * t - std::floor(hz * t);
  return phase < duty ? on : (1.0 - depth) * on;
}

double Flicker::MeanOverExposure(double t, double exposure) const {
  if (!enabled()) return 1.0;
  if (!(exposure > 0.0)) return Intensity(t);
  if (duty <= 0.0) {
    const double x = kPi * hz * exposure;
    return 1.0 + depth * std::cos(2.0 * kPi * hz * t) * std::sin(x) / x;
  }
  const double on = 1.0 / (duty + (1.0 - duty) * (1.0 - depth)), off = (1.0 - depth) * on;
  const double a = hz * (t - 0.5 * exposure), b = hz * (t + 0.5 * exposure);
  const double on_fraction = (OnPeriods(b, duty) - OnPeriods(a, duty)) / (b - a);
  return off + (on - off) * on_fraction;
}

bool Flicker::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(hz >= 0.0) || !std::isfinite(hz))
    os << "the frequency " << hz << " Hz must be >= 0";
  else if (!(depth >= 0.0 && depth <= 1.0))
    os << "the depth " << depth << " must be in [0, 1]";
  else if (!(duty >= 0.0 && duty < 1.0))
    os << "the duty cycle " << duty << " must be in (0, 1) (0: a ripple)";
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

double DepthOfField::CirclePx(double fx, double depth_m) const {
  if (!enabled()) return 0.0;
  const double f = fx * pixel_pitch_m, s = focus_distance_m;
  const double aperture = f / f_number;
  const double defocus = std::isinf(depth_m) ? 1.0 : std::abs(depth_m - s) / depth_m;
  return fx * aperture * defocus / (s - f);
}

bool DepthOfField::IsValid(std::string* error) const {
  std::ostringstream os;
  if (!(f_number >= 0.0) || !std::isfinite(f_number))
    os << "the f-number " << f_number << " must be > 0";
  else if (enabled() && (!(focus_distance_m > 0.0) || !std::isfinite(focus_distance_m)))
    os << "the focus distance " << focus_distance_m << " m must be > 0";
  else if (!(pixel_pitch_m > 0.0) || !std::isfinite(pixel_pitch_m))
    os << "the pixel pitch " << pixel_pitch_m << " m must be > 0";
  if (os.str().empty()) return true;
  if (error) *error = os.str();
  return false;
}

namespace {

// A disc kernel: the disc's area in each pixel of (2 r + 1)^2, summing to 1.
struct DiscKernel {
  int r = 0;
  std::vector<float> weights;
};

// The disc of diameter `diameter` px (quantised to 1/20 px), from 8 x 8 samples per pixel.
const DiscKernel& DiscOf(double diameter) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<DiscKernel>> cache;
  const int key = static_cast<int>(std::lround(diameter * 20.0));
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[key];
  if (slot) return *slot;
  slot = std::make_unique<DiscKernel>();
  const double radius = 0.5 * key / 20.0, r2 = radius * radius;
  const int r = static_cast<int>(std::ceil(radius + 0.5));
  slot->r = r;
  const int side = 2 * r + 1;
  slot->weights.assign(static_cast<size_t>(side) * side, 0.0f);
  constexpr int kSamples = 8;
  double total = 0.0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      int inside = 0;
      for (int b = 0; b < kSamples; ++b)
        for (int a = 0; a < kSamples; ++a) {
          const double x = dx - 0.5 + (a + 0.5) / kSamples, y = dy - 0.5 + (b + 0.5) / kSamples;
          inside += x * x + y * y <= r2;
        }
      slot->weights[static_cast<size_t>(dy + r) * side + dx + r] = static_cast<float>(inside);
      total += inside;
    }
  if (total <= 0.0) {  // smaller than a sample: the pixel itself
    slot->weights[static_cast<size_t>(r) * side + r] = 1.0f;
    total = 1.0;
  }
  for (float& w : slot->weights) w = static_cast<float>(w / total);
  return *slot;
}

}  // namespace

cv::Mat ApplyDepthOfField(const cv::Mat& linear_bgr, const cv::Mat& depth, double fx,
                          const DepthOfField& dof) {
  if (linear_bgr.type() != CV_32FC3 || depth.type() != CV_32F || depth.size() != linear_bgr.size())
    throw std::invalid_argument(
        "ApplyDepthOfField: a CV_32FC3 image and a CV_32F depth map of "
        "its size");
  cv::Mat out(linear_bgr.size(), CV_32FC3, cv::Scalar::all(0));
  const int width = linear_bgr.cols, height = linear_bgr.rows;
  for (int y = 0; y < height; ++y) {
    const cv::Vec3f* in = linear_bgr.ptr<cv::Vec3f>(y);
    const float* z = depth.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      const cv::Vec3f light = in[x];
      if (light[0] == 0.0f && light[1] == 0.0f && light[2] == 0.0f) continue;
      const double c = dof.CirclePx(fx, z[x]);
      if (c < 0.5) {  // within the pixel
        out.at<cv::Vec3f>(y, x) += light;
        continue;
      }
      const DiscKernel& disc = DiscOf(c);
      const int r = disc.r, side = 2 * r + 1;
      for (int dy = -r; dy <= r; ++dy) {
        // Light spread beyond the image's edge is lost, as on a real sensor.
        const int yy = y + dy;
        if (yy < 0 || yy >= height) continue;
        cv::Vec3f* row = out.ptr<cv::Vec3f>(yy);
        const float* w = &disc.weights[static_cast<size_t>(dy + r) * side + r];
        for (int dx = std::max(-r, -x); dx <= std::min(r, width - 1 - x); ++dx)
          if (w[dx] > 0.0f) row[x + dx] += w[dx] * light;
      }
    }
  }
  return out;
}

std::vector<CameraResponse> DrawCameraResponses(int cameras, double sigma, uint64_t seed) {
  std::vector<CameraResponse> responses(cameras);
  if (!(sigma > 0.0)) return responses;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 17);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int c = 0; c < cameras; ++c) {
    CameraResponse& r = responses[c];
    for (double& w : r.white_balance) w = std::exp(sigma * normal(rng));
    r.gain = std::exp(sigma * normal(rng));
    r.gamma = std::exp(0.5 * sigma * normal(rng));
    r.prnu = std::min(1.0, 0.1 * sigma);
    r.dsnu = std::min(255.0, 10.0 * sigma);
    r.hot_pixels = std::min(1.0, 1e-3 * sigma);
    r.pattern_seed = seed * 7717 + static_cast<uint64_t>(c) * 131 + 5;
  }
  return responses;
}

std::vector<CameraResponse> ReadCameraResponses(const std::string& path, const calib::Rig& rig) {
  const YAML::Node root = LoadYamlFile(path);
  std::vector<CameraResponse> responses(rig.cameras.size());
  for (size_t c = 0; c < responses.size(); ++c)
    responses[c].pattern_seed = 1000 + static_cast<uint64_t>(c);
  const YAML::Node cameras = root["cameras"];
  if (!cameras || !cameras.IsMap())
    throw InputError(path + ": expected a map 'cameras:' of camera name to its response");
  for (const auto& item : cameras) {
    const std::string name = item.first.as<std::string>();
    const int c = rig.Find(name);
    if (c < 0) throw InputError(path + ": cameras." + name + ": the rig has no such camera");
    const YAML::Node node = item.second;
    const std::string where = path + ": cameras." + name;
    if (!node.IsMap()) throw InputError(where + ": expected a map of response values");
    CameraResponse& r = responses[c];
    auto number = [&](const char* key, double* value) {
      const YAML::Node v = node[key];
      if (!v) return;
      try {
        *value = v.as<double>();
      } catch (const YAML::Exception&) {
        throw InputError(where + "." + key + ": expected a number");
      }
    };
    for (const auto& key : node) {
      const std::string k = key.first.as<std::string>();
      if (k != "white_balance" && k != "gain" && k != "gamma" && k != "prnu" && k != "dsnu" &&
          k != "hot_pixels" && k != "seed")
        throw InputError(where + "." + k +
                         ": unknown key (white_balance, gain, gamma, prnu, "
                         "dsnu, hot_pixels, seed)");
    }
    if (const YAML::Node wb = node["white_balance"]) {
      if (!wb.IsSequence() || wb.size() != 3)
        throw InputError(where + ".white_balance: expected [R, G, B] gains");
      try {
        // The file says R, G, B; the response keeps B, G, R as the images do.
        for (int i = 0; i < 3; ++i) r.white_balance[2 - i] = wb[i].as<double>();
      } catch (const YAML::Exception&) {
        throw InputError(where + ".white_balance: expected [R, G, B] gains");
      }
    }
    number("gain", &r.gain);
    number("gamma", &r.gamma);
    number("prnu", &r.prnu);
    number("dsnu", &r.dsnu);
    number("hot_pixels", &r.hot_pixels);
    double seed = static_cast<double>(r.pattern_seed);
    number("seed", &seed);
    if (!(seed >= 0.0 && seed < 9e15))
      throw InputError(where + ".seed: expected a whole number >= 0");
    r.pattern_seed = static_cast<uint64_t>(seed);
    std::string error;
    if (!r.IsValid(&error)) throw InputError(where + ": " + error);
  }
  return responses;
}

LampRig PaperLamps(const calib::Rig& rig, const Eigen::Vector3d& aim) {
  LampRig rig_lamps;
  rig_lamps.glossy = 0.25;
  double sum = 0.0;
  for (const calib::Camera& camera : rig.cameras) {
    const Eigen::Vector3d c = camera.Center();
    Lamp lamp;
    lamp.position = c + Eigen::Vector3d(0.0, c.y() < 0.0 ? -0.15 : 0.15, 0.0);
    sum += 1.0 / (lamp.position - aim).squaredNorm();
    rig_lamps.lamps.push_back(lamp);
  }
  for (Lamp& lamp : rig_lamps.lamps) lamp.power = (1.0 - rig_lamps.ambient) / sum;
  return rig_lamps;
}

LampRig ReadLamps(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  LampRig rig;
  auto number = [&](const YAML::Node& node, const std::string& key, double* value) {
    if (!node[key]) return;
    try {
      *value = node[key].as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(path + ": " + key + ": expected a number");
    }
    if (!std::isfinite(*value)) throw InputError(path + ": " + key + ": expected a number");
  };
  if (!root.IsMap()) throw InputError(path + ": expected a map with 'lamps:'");
  number(root, "ambient", &rig.ambient);
  number(root, "glossy", &rig.glossy);
  number(root, "shininess", &rig.shininess);
  if (!(rig.ambient >= 0.0 && rig.ambient <= 1.0))
    throw InputError(path + ": ambient must be in [0, 1]");
  if (!(rig.glossy >= 0.0)) throw InputError(path + ": glossy must be >= 0");
  if (!(rig.shininess > 0.0)) throw InputError(path + ": shininess must be > 0");
  const YAML::Node lamps = root["lamps"];
  if (!lamps || !lamps.IsSequence() || lamps.size() == 0)
    throw InputError(path + ": lamps: expected a list of {position: [x, y, z], power}");
  for (size_t i = 0; i < lamps.size(); ++i) {
    const std::string where = "lamps[" + std::to_string(i) + "]";
    const YAML::Node position = lamps[i]["position"];
    Lamp lamp;
    if (!position || !position.IsSequence() || position.size() != 3)
      throw InputError(path + ": " + where + ": expected {position: [x, y, z], power}");
    try {
      for (int a = 0; a < 3; ++a) lamp.position[a] = position[a].as<double>();
      lamp.power = lamps[i]["power"] ? lamps[i]["power"].as<double>() : 1.0;
    } catch (const YAML::Exception&) {
      throw InputError(path + ": " + where + ": expected {position: [x, y, z], power}");
    }
    if (!lamp.position.allFinite() || !(lamp.power >= 0.0) || !std::isfinite(lamp.power))
      throw InputError(path + ": " + where + ": the position must be finite, the power >= 0");
    rig.lamps.push_back(lamp);
  }
  return rig;
}

Eigen::Vector3d CameraMotion::Displacement(double t) const {
  if (!enabled()) return Eigen::Vector3d::Zero();
  if (hz > 0.0) return amplitude_m * std::sin(2.0 * kPi * hz * t + phase) * direction;
  return t >= step_time ? Eigen::Vector3d(amplitude_m * direction) : Eigen::Vector3d::Zero();
}

calib::Camera CameraMotion::At(const calib::Camera& camera, double t) const {
  if (!enabled()) return camera;
  calib::Camera moved = camera;
  // x_cam = R (x - C): moving C by D moves the translation by -R D.
  moved.cam_from_world.translation -= camera.cam_from_world.rotation * Displacement(t);
  return moved;
}

CameraMotion DrawCameraMotion(double amplitude_m, double hz, double step_time, uint64_t seed,
                              int c) {
  std::mt19937_64 rng(seed * 0x2545F4914F6CDD1Dull + static_cast<uint64_t>(c) * 977 + 3);
  std::normal_distribution<double> normal(0.0, 1.0);
  CameraMotion motion;
  motion.amplitude_m = amplitude_m;
  motion.hz = hz;
  motion.step_time = step_time;
  Eigen::Vector3d d(normal(rng), normal(rng), normal(rng));
  motion.direction = d.norm() > 0.0 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d::UnitX();
  motion.phase = std::uniform_real_distribution<double>(0.0, 2.0 * kPi)(rng);
  return motion;
}

cv::Mat TextileBackground(const calib::CameraIntrinsics& intrinsics, double albedo, bool clutter,
                          uint64_t seed) {
  const int width = intrinsics.width, height = intrinsics.height;
  std::mt19937_64 rng(seed * 6364136223846793005ull + 11);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Folds: ridges of the cloth's height h = sum a sin(k . p + phi) (p in units of the image
  // width), their slope tilting the normal; Lambert from a light 40 degrees off the panel normal.
  struct Fold {
    Eigen::Vector2d k;
    double amplitude, phase;
  };
  std::vector<Fold> folds;
  for (int i = 0; i < 5; ++i) {
    const double angle = kPi * uniform(rng), wavelength = 0.15 + 0.35 * uniform(rng);
    folds.push_back({2.0 * kPi / wavelength * Eigen::Vector2d(std::cos(angle), std::sin(angle)),
                     0.012 * wavelength * (0.5 + uniform(rng)), 2.0 * kPi * uniform(rng)});
  }
  const Eigen::Vector3d light = Eigen::Vector3d(0.45, -0.45, 1.0).normalized();
  const double flat = light.z();
  cv::Mat image(height, width, CV_32FC3);
  const double scale = 1.0 / width;
  for (int y = 0; y < height; ++y) {
    cv::Vec3f* row = image.ptr<cv::Vec3f>(y);
    for (int x = 0; x < width; ++x) {
      const Eigen::Vector2d p(x * scale, y * scale);
      Eigen::Vector2d slope = Eigen::Vector2d::Zero();
      for (const Fold& f : folds) slope += f.amplitude * std::cos(f.k.dot(p) + f.phase) * f.k;
      const Eigen::Vector3d normal = Eigen::Vector3d(-slope.x(), -slope.y(), 1.0).normalized();
      const double shade = std::max(0.0, normal.dot(light)) / flat;
      // A plain weave: threads over and under in a 2-px check.
      const double weave = ((x >> 1) + (y >> 1)) & 1 ? 1.08 : 0.92;
      const float value = static_cast<float>(albedo * shade * weave);
      row[x] = cv::Vec3f(value, value, value);
    }
  }
  if (clutter) {
    // The rig's structure along the edges: aluminium profiles (bright, with a groove) across
    // two edges and bolts at seeded places.
    const int bar = std::max(2, width / 40);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < bar; ++x) {
        const float v = (x == bar / 2) ? 0.2f : 0.75f;
        image.at<cv::Vec3f>(y, x) = cv::Vec3f(v, v, v * 1.05f);
      }
    for (int y = height - bar; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const float v = (y == height - bar / 2 - 1) ? 0.2f : 0.7f;
        image.at<cv::Vec3f>(y, x) = cv::Vec3f(v, v, v * 1.05f);
      }
    for (int i = 0; i < 12; ++i) {
      const int cx = static_cast<int>(uniform(rng) * width);
      const int cy = static_cast<int>(uniform(rng) * height);
      if (cx > 3 * bar && cy < height - 3 * bar) continue;  // only near the edges
      const int r = std::max(1, bar / 3);
      for (int y = std::max(0, cy - r); y <= std::min(height - 1, cy + r); ++y)
        for (int x = std::max(0, cx - r); x <= std::min(width - 1, cx + r); ++x)
          if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r)
            image.at<cv::Vec3f>(y, x) = cv::Vec3f(0.95f, 0.95f, 0.95f);
    }
  }
  return image;
}

}  // namespace netlab::recon
