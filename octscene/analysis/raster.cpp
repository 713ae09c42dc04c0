#include "raster.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <fstream>
#include <numbers>

// Third-party single-file headers: their own warnings are not ours to fix.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb_easy_font.h>
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace octbake::scene {

Raster::Raster(int width, int height, Rgb background)
    : width_(width),
      height_(height),
      rgb_(static_cast<size_t>(width) * height * 3),
      inv_z_(static_cast<size_t>(width) * height, 0.0f),
      kind_(static_cast<size_t>(width) * height, PixelKind::background) {
  assert(width > 0 && height > 0);
  for (size_t i = 0; i < inv_z_.size(); ++i) {
    rgb_[3 * i] = background.r, rgb_[3 * i + 1] = background.g, rgb_[3 * i + 2] = background.b;
  }
}

Rgb Raster::pixel(int x, int y) const {
  const size_t i = 3 * index(x, y);
  return {rgb_[i], rgb_[i + 1], rgb_[i + 2]};
}

size_t Raster::count(PixelKind k) const { return static_cast<size_t>(std::count(kind_.begin(), kind_.end(), k)); }

namespace {

// v / |v|: v first scaled by a power of two to largest coordinate in [1, 2)
// (exact, coordinate by coordinate), so |v|^2 neither over- nor underflows
// (a camera 2^600 from its target) and the result is normalized()'s, bit for
// bit, wherever that one did not.
Eigen::Vector3d direction(const Eigen::Vector3d& v) {
  const double m = v.cwiseAbs().maxCoeff();
  if (!(m > 0) || !std::isfinite(m)) return v.normalized();
  const int e = std::ilogb(m);
  return v.unaryExpr([e](double x) { return std::ldexp(x, -e); }).normalized();
}

}  // namespace

void Raster::set_camera(const Camera& camera) {
  eye_ = camera.position;
  forward_ = direction(camera.look_at - camera.position);
  right_ = direction(forward_.cross(camera.up));
  up_ = right_.cross(forward_);
  focal_ = 0.5 * height_ / std::tan(0.5 * camera.fov_y_deg * std::numbers::pi / 180.0);
  inv_unit_ = camera.near_plane > 0 && std::isnormal(camera.near_plane)
                  ? std::ldexp(1.0, -std::ilogb(camera.near_plane))
                  : 1.0;
  near_ = camera.near_plane * inv_unit_;
}

Eigen::Vector3d Raster::to_camera(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = (p - eye_) * inv_unit_;
  return {d.dot(right_), d.dot(up_), d.dot(forward_)};
}

Raster::Projected Raster::project(const Eigen::Vector3d& c) const {
  return {0.5 * width_ + focal_ * c.x() / c.z(), 0.5 * height_ - focal_ * c.y() / c.z(), 1.0 / c.z()};
}

void Raster::blend(int x, int y, Rgb color, double alpha, PixelKind kind) {
  const size_t i = 3 * index(x, y);
  auto mix = [alpha](uint8_t under, uint8_t over) {
    return static_cast<uint8_t>(std::lround(under * (1 - alpha) + over * alpha));
  };
  rgb_[i] = mix(rgb_[i], color.r), rgb_[i + 1] = mix(rgb_[i + 1], color.g), rgb_[i + 2] = mix(rgb_[i + 2], color.b);
  if (alpha >= 0.5) kind_[index(x, y)] = kind;
}

void Raster::triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, Rgb color) {
  const std::array<Eigen::Vector3d, 3> cam{to_camera(a), to_camera(b), to_camera(c)};
  const Eigen::Vector3d normal = (cam[1] - cam[0]).cross(cam[2] - cam[0]);
  if (normal.squaredNorm() == 0) return;
  static const Eigen::Vector3d kLight = Eigen::Vector3d(-0.3, 0.45, -1).normalized();  // eye side, up left
  const double shade = 0.25 + 0.75 * std::abs(normal.normalized().dot(kLight));
  const Rgb lit{static_cast<uint8_t>(color.r * shade), static_cast<uint8_t>(color.g * shade),
                static_cast<uint8_t>(color.b * shade)};

  // Clip against the near plane (Sutherland-Hodgman, one plane).
  std::array<Eigen::Vector3d, 4> poly;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& p = cam[i];
    const Eigen::Vector3d& q = cam[(i + 1) % 3];
    const bool p_in = p.z() >= near_, q_in = q.z() >= near_;
    if (p_in) poly[n++] = p;
    if (p_in != q_in) poly[n++] = p + (q - p) * ((near_ - p.z()) / (q.z() - p.z()));
  }
  for (int k = 1; k + 1 < n; ++k) {
    const Projected v[3] = {project(poly[0]), project(poly[k]), project(poly[k + 1])};
    auto edge = [](const Projected& p, const Projected& q, double x, double y) {
      return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
    };
    const double area = edge(v[0], v[1], v[2].x, v[2].y);
    if (std::abs(area) < 1e-12) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({v[0].x, v[1].x, v[2].x}))));
    const int x1 = std::min(width_ - 1, static_cast<int>(std::ceil(std::max({v[0].x, v[1].x, v[2].x}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({v[0].y, v[1].y, v[2].y}))));
    const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(std::max({v[0].y, v[1].y, v[2].y}))));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = edge(v[1], v[2], px, py) / area, w1 = edge(v[2], v[0], px, py) / area;
        const double w2 = 1 - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float inv_z = static_cast<float>(w0 * v[0].inv_z + w1 * v[1].inv_z + w2 * v[2].inv_z);
        const size_t i = index(x, y);
        if (inv_z <= inv_z_[i]) continue;
        inv_z_[i] = inv_z;
        blend(x, y, lit, 1.0, PixelKind::surface);
      }
    }
  }
}

void Raster::line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Rgb color, double alpha_visible,
                  double alpha_hidden) {
  Eigen::Vector3d p = to_camera(a), q = to_camera(b);
  if (p.z() < near_ && q.z() < near_) return;
  if (p.z() < near_) p = p + (q - p) * ((near_ - p.z()) / (q.z() - p.z()));
  if (q.z() < near_) q = q + (p - q) * ((near_ - q.z()) / (p.z() - q.z()));
  const Projected s = project(p), e = project(q);
  const double span = std::max(std::abs(e.x - s.x), std::abs(e.y - s.y));
  if (!(span < 1e5)) return;  // absurdly long after projection: not worth drawing
  const int steps = static_cast<int>(std::ceil(span)) + 1;
  for (int k = 0; k <= steps; ++k) {
    const double t = double(k) / steps;
    const int x = static_cast<int>(std::floor(s.x + (e.x - s.x) * t));
    const int y = static_cast<int>(std::floor(s.y + (e.y - s.y) * t));
    if (x < 0 || y < 0 || x >= width_ || y >= height_) continue;
    // 1/z is linear in screen space; a small bias keeps edges lying on the
    // surface visible.
    const double inv_z = s.inv_z + (e.inv_z - s.inv_z) * t;
    const bool visible = inv_z >= inv_z_[index(x, y)] * (1 - 1e-3);
    blend(x, y, color, visible ? alpha_visible : alpha_hidden, PixelKind::line);
  }
}

namespace {
std::array<Eigen::Vector3d, 8> corners(const OrientedBox& box) {
  std::array<Eigen::Vector3d, 8> c;
  for (int j = 0; j < 8; ++j) {
    const Eigen::Vector3d s((j & 1) ? 1 : -1, (j & 2) ? 1 : -1, (j & 4) ? 1 : -1);
    c[j] = box.center + box.axes * s.cwiseProduct(box.half);
  }
  return c;
}
}  // namespace

void Raster::box_edges(const OrientedBox& box, Rgb color, double alpha_visible, double alpha_hidden) {
  const auto c = corners(box);
  for (int j = 0; j < 8; ++j) {
    for (int bit = 1; bit < 8; bit <<= 1) {
      if (!(j & bit)) line(c[j], c[j | bit], color, alpha_visible, alpha_hidden);
    }
  }
}

void Raster::box_faces(const OrientedBox& box, Rgb color) {
  const auto c = corners(box);
  // Each face: the 4 corners with one bit fixed, in cyclic order.
  for (int bit = 1; bit < 8; bit <<= 1) {
    const int u = bit == 1 ? 2 : 1, v = bit == 4 ? 2 : 4;
    for (int side : {0, bit}) {
      triangle(c[side], c[side | u], c[side | u | v], color);
      triangle(c[side], c[side | u | v], c[side | v], color);
    }
  }
}

void Raster::fill_rect(int x, int y, int w, int h, Rgb color) {
  for (int yy = std::max(0, y); yy < std::min(height_, y + h); ++yy) {
    for (int xx = std::max(0, x); xx < std::min(width_, x + w); ++xx) blend(xx, yy, color, 1.0, PixelKind::overlay);
  }
}

int Raster::text(int x, int y, const std::string& s, Rgb color, int scale) {
  struct Vertex {
    float x, y, z;
    unsigned char rgba[4];
  };
  std::vector<Vertex> buffer(s.size() * 64 + 64);  // stb's estimate is ~270 bytes a character
  std::string copy = s;
  const int quads = stb_easy_font_print(0, 0, copy.data(), nullptr, buffer.data(),
                                        static_cast<int>(buffer.size() * sizeof(Vertex)));
  for (int q = 0; q < quads; ++q) {
    const Vertex* v = &buffer[4 * q];
    const float qx0 = std::min({v[0].x, v[1].x, v[2].x, v[3].x}), qx1 = std::max({v[0].x, v[1].x, v[2].x, v[3].x});
    const float qy0 = std::min({v[0].y, v[1].y, v[2].y, v[3].y}), qy1 = std::max({v[0].y, v[1].y, v[2].y, v[3].y});
    fill_rect(x + static_cast<int>(qx0 * scale), y + static_cast<int>(qy0 * scale),
              static_cast<int>((qx1 - qx0) * scale), static_cast<int>((qy1 - qy0) * scale), color);
  }
  return stb_easy_font_width(copy.data()) * scale;
}

void Raster::blit(const Raster& src, int x, int y) {
  for (int sy = 0; sy < src.height_; ++sy) {
    for (int sx = 0; sx < src.width_; ++sx) {
      const int dx = x + sx, dy = y + sy;
      if (dx < 0 || dy < 0 || dx >= width_ || dy >= height_) continue;
      const size_t s = src.index(sx, sy), d = index(dx, dy);
      std::copy_n(&src.rgb_[3 * s], 3, &rgb_[3 * d]);
      kind_[d] = src.kind_[s];
      inv_z_[d] = src.inv_z_[s];
    }
  }
}

std::vector<uint8_t> Raster::encode_png() const {
  std::vector<uint8_t> out;
  auto append = [](void* context, void* data, int size) {
    auto* bytes = static_cast<std::vector<uint8_t>*>(context);
    bytes->insert(bytes->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
  };
  if (!stbi_write_png_to_func(append, &out, width_, height_, 3, rgb_.data(), width_ * 3)) out.clear();
  return out;
}

bool Raster::write_png(const std::string& path) const {
  const std::vector<uint8_t> png = encode_png();
  if (png.empty()) return false;
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  return static_cast<bool>(out);
}

}  // namespace octbake::scene
