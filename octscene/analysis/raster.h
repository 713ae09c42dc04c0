// A small software rasteriser for `octscene picture`: perspective camera,
// z-buffer, flat-shaded triangles, depth-aware lines, bitmap text, PNG out.
// Every pixel also records what was drawn last (PixelKind) so tests can check
// the picture without decoding colours.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "octbake/lod.h"
#include "octbake/pose.h"

namespace octbake::scene {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

enum class PixelKind : uint8_t { background, surface, line, overlay };

class Raster {
 public:
  Raster(int width, int height, Rgb background);

  int width() const { return width_; }
  int height() const { return height_; }
  Rgb pixel(int x, int y) const;
  PixelKind kind(int x, int y) const { return kind_[index(x, y)]; }
  size_t count(PixelKind k) const;
  std::span<const uint8_t> rgb() const { return rgb_; }  // row major, 3 bytes a pixel

  // Perspective view through `camera` (position, look_at, up, fov_y_deg,
  // near/far); the raster's own size sets the aspect, not camera.viewport.
  void set_camera(const Camera& camera);

  // Flat shaded by the face normal against a light near the eye (two sided),
  // clipped at the near plane, z-buffered.
  void triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, Rgb color);
  // A one-pixel line blended over the picture: with `alpha_visible` where it
  // is in front of the surface drawn so far, `alpha_hidden` where behind it.
  void line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Rgb color, double alpha_visible, double alpha_hidden);
  void box_edges(const OrientedBox& box, Rgb color, double alpha_visible, double alpha_hidden);
  void box_faces(const OrientedBox& box, Rgb color);

  // Screen-space overlays (legends, labels), drawn without depth.
  void fill_rect(int x, int y, int w, int h, Rgb color);
  // stb_easy_font text, each font pixel `scale` pixels wide; returns its width.
  int text(int x, int y, const std::string& s, Rgb color, int scale);
  // Copies `src` with its top-left corner at (x, y), clipped.
  void blit(const Raster& src, int x, int y);

  bool write_png(const std::string& path) const;
  std::vector<uint8_t> encode_png() const;

 private:
  struct Projected {
    double x, y, inv_z;  // pixel coordinates, 1 / camera depth
  };
  size_t index(int x, int y) const { return static_cast<size_t>(y) * width_ + x; }
  Eigen::Vector3d to_camera(const Eigen::Vector3d& p) const;
  Projected project(const Eigen::Vector3d& c) const;
  void blend(int x, int y, Rgb color, double alpha, PixelKind kind);

  int width_, height_;
  std::vector<uint8_t> rgb_;
  std::vector<float> inv_z_;  // 0 = nothing drawn (infinitely far)
  std::vector<PixelKind> kind_;
  Eigen::Vector3d eye_{0, 0, 0}, right_{1, 0, 0}, up_{0, 1, 0}, forward_{0, 0, 1};
  double focal_ = 1, near_ = 0.1;
  // Camera space is in units of a power of two near the near plane (its
  // inverse here): exact, so the pixels are the same at any scale, and the
  // float inverse depths neither over- nor underflow for a scene at 2^±1000.
  double inv_unit_ = 1;
};

}  // namespace octbake::scene
