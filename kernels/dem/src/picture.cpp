// Cairo drawing of the section slab and the discharge curve; PNG bytes streamed into an
// atomically written file.
#include "contactlab/dem/picture.hpp"

#include <cairo.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <ostream>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {
namespace {

// Room around the plot for the axes' labels, the title and the legend [px].
constexpr int kLeft = 70, kRight = 170, kTop = 40, kBottom = 50;

struct Rgb {
  double r, g, b;
};
// Neighbouring bands in well-separated hues (matplotlib's tab10 order).
constexpr std::array<Rgb, 10> kPalette{{{0.122, 0.467, 0.706},
                                        {1.000, 0.498, 0.055},
                                        {0.173, 0.627, 0.173},
                                        {0.839, 0.153, 0.157},
                                        {0.580, 0.404, 0.741},
                                        {0.549, 0.337, 0.294},
                                        {0.890, 0.467, 0.761},
                                        {0.498, 0.498, 0.498},
                                        {0.737, 0.741, 0.133},
                                        {0.090, 0.745, 0.812}}};

Rgb layer_colour(int layer) { return kPalette[static_cast<std::size_t>(layer) % kPalette.size()]; }

// A tick spacing of 1, 2 or 5 x 10^k giving about `ticks` ticks over `span`.
double nice_step(double span, int ticks) {
  const double raw = span / std::max(1, ticks);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

// An owned cairo surface and context, written out as PNG bytes.
class Canvas {
 public:
  Canvas(int width, int height)
      : surface_(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height)),
        cr_(cairo_create(surface_)) {
    cairo_set_source_rgb(cr_, 1, 1, 1);
    cairo_paint(cr_);
    cairo_select_font_face(cr_, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr_, 13);
  }
  ~Canvas() {
    cairo_destroy(cr_);
    cairo_surface_destroy(surface_);
  }
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;
  cairo_t* cr() const { return cr_; }

  void text(double x, double y, const std::string& s, double align = 0.0) const {
    cairo_text_extents_t e;
    cairo_text_extents(cr_, s.c_str(), &e);
    cairo_move_to(cr_, x - align * e.x_advance, y);
    cairo_show_text(cr_, s.c_str());
  }
  void line(double x0, double y0, double x1, double y1) const {
    cairo_move_to(cr_, x0, y0);
    cairo_line_to(cr_, x1, y1);
    cairo_stroke(cr_);
  }
  void save(const std::string& path) const {
    cairo_surface_flush(surface_);
    write_file_atomically(
        path,
        [&](std::ostream& out) {
          const cairo_status_t status = cairo_surface_write_to_png_stream(
              surface_,
              [](void* closure, const unsigned char* data, unsigned int length) {
                static_cast<std::ostream*>(closure)->write(reinterpret_cast<const char*>(data),
                                                           length);
                return CAIRO_STATUS_SUCCESS;
              },
              &out);
          if (status != CAIRO_STATUS_SUCCESS) {
            throw InputError(path +
                             ": cairo could not encode the PNG: " + cairo_status_to_string(status));
          }
        },
        true);
  }

 private:
  cairo_surface_t* surface_;
  cairo_t* cr_;
};

// Axis ticks and labels of a plot area [px0, px1] x [py0, py1] showing [x0, x1] x [y0, y1].
struct Frame {
  double px0, px1, py0, py1;
  double x0, x1, y0, y1;
  double px(double x) const { return px0 + (x - x0) / (x1 - x0) * (px1 - px0); }
  double py(double y) const { return py1 - (y - y0) / (y1 - y0) * (py1 - py0); }
};

void draw_axes(const Canvas& c, const Frame& f, double scale, const std::string& x_label,
               const std::string& y_label) {
  cairo_t* cr = c.cr();
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, f.px0, f.py0, f.px1 - f.px0, f.py1 - f.py0);
  cairo_stroke(cr);
  const double sx = nice_step(f.x1 - f.x0, 6), sy = nice_step(f.y1 - f.y0, 6);
  for (double x = std::ceil(f.x0 / sx) * sx; x <= f.x1 + 1e-9 * sx; x += sx) {
    c.line(f.px(x), f.py1, f.px(x), f.py1 + 5);
    c.text(f.px(x), f.py1 + 18, fmt::format("{:g}", std::round(x * scale * 1e6) / 1e6 + 0.0), 0.5);
  }
  for (double y = std::ceil(f.y0 / sy) * sy; y <= f.y1 + 1e-9 * sy; y += sy) {
    c.line(f.px0 - 5, f.py(y), f.px0, f.py(y));
    c.text(f.px0 - 8, f.py(y) + 4, fmt::format("{:g}", std::round(y * scale * 1e6) / 1e6 + 0.0),
           1.0);
  }
  c.text(0.5 * (f.px0 + f.px1), f.py1 + 38, x_label, 0.5);
  cairo_save(cr);
  cairo_translate(cr, 16, 0.5 * (f.py0 + f.py1));
  cairo_rotate(cr, -std::numbers::pi / 2);
  c.text(0, 0, y_label, 0.5);
  cairo_restore(cr);
}

}  // namespace

SectionView section_view_for(const EngineSettings& settings, const Particles& initial) {
  SectionView v;
  const Domain& d = settings.domain;
  v.axis_x = 0.5 * (d.lo[0] + d.hi[0]);
  v.axis_y = 0.5 * (d.lo[1] + d.hi[1]);
  for (const Wall& w : settings.walls) {
    if (w.kind == WallKind::kCylinder && std::abs(w.normal[2]) > 0.999) {
      v.axis_x = w.point[0];
      v.axis_y = w.point[1];
      break;
    }
  }
  double max_r = 0.0;
  for (double r : initial.radius) max_r = std::max(max_r, r);
  v.slab_half_width = 4.0 * max_r;
  v.x_lo = d.lo[0];
  v.x_hi = d.hi[0];
  v.z_lo = d.lo[2];
  v.z_hi = d.hi[2];
  return v;
}

std::vector<std::uint8_t> height_layers(const Particles& initial, int layers) {
  std::uint32_t capacity = 0;
  for (std::uint32_t id : initial.id) capacity = std::max(capacity, id + 1);
  std::vector<std::uint8_t> band(capacity, 0);
  std::vector<std::uint32_t> order(initial.size());
  std::iota(order.begin(), order.end(), 0u);
  // Ties broken by id: the bands do not depend on the particles' array order.
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return initial.z[a] != initial.z[b] ? initial.z[a] < initial.z[b]
                                        : initial.id[a] < initial.id[b];
  });
  const std::size_t n = order.size();
  for (std::size_t rank = 0; rank < n; ++rank) {
    band[initial.id[order[rank]]] =
        static_cast<std::uint8_t>(rank * static_cast<std::size_t>(layers) / n);
  }
  return band;
}

SectionPainter::SectionPainter(std::string dir, std::string name, SectionView view,
                               std::vector<std::uint8_t> layer_of_id)
    : dir_(std::move(dir)),
      name_(std::move(name)),
      view_(view),
      layer_of_id_(std::move(layer_of_id)) {
  if (!dir_.empty() && dir_.back() != '/') dir_ += '/';
  if (!(view_.x_hi > view_.x_lo && view_.z_hi > view_.z_lo) || view_.plot_width_px < 50 ||
      view_.layers < 1) {
    throw InputError("section picture: empty window or plot narrower than 50 px");
  }
  prepare_output_file(frame_path(0));
}

std::string SectionPainter::frame_path(int frame) const {
  return dir_ + fmt::format("{}_section_{:05d}.png", name_, frame);
}

int SectionPainter::width() const { return kLeft + view_.plot_width_px + kRight; }

int SectionPainter::height() const {
  const double aspect = (view_.z_hi - view_.z_lo) / (view_.x_hi - view_.x_lo);
  return kTop + static_cast<int>(std::lround(view_.plot_width_px * aspect)) + kBottom;
}

void SectionPainter::write(const Snapshot& run, int frame) const {
  Canvas canvas(width(), height());
  cairo_t* cr = canvas.cr();
  const Frame f{kLeft,      static_cast<double>(kLeft + view_.plot_width_px),
                kTop,       static_cast<double>(height() - kBottom),
                view_.x_lo, view_.x_hi,
                view_.z_lo, view_.z_hi};
  const double px_per_m = view_.plot_width_px / (view_.x_hi - view_.x_lo);
  cairo_save(cr);
  cairo_rectangle(cr, f.px0, f.py0, f.px1 - f.px0, f.py1 - f.py0);
  cairo_clip(cr);
  // Spheres of the slab, the far side first (the near ones on top).
  const Particles& p = run.particles;
  std::vector<std::uint32_t> slab;
  for (std::size_t a = 0; a < p.size(); ++a) {
    if (std::abs(p.y[a] - view_.axis_y) < view_.slab_half_width) {
      slab.push_back(static_cast<std::uint32_t>(a));
    }
  }
  std::sort(slab.begin(), slab.end(), [&](std::uint32_t a, std::uint32_t b) {
    return p.y[a] != p.y[b] ? p.y[a] > p.y[b] : p.id[a] < p.id[b];
  });
  cairo_set_line_width(cr, 0.5);
  for (std::uint32_t a : slab) {
    const int layer = p.id[a] < layer_of_id_.size() ? layer_of_id_[p.id[a]] : 0;
    const Rgb c = layer_colour(layer);
    cairo_arc(cr, f.px(p.x[a]), f.py(p.z[a]), std::max(0.5, p.radius[a] * px_per_m), 0,
              2 * std::numbers::pi);
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
    cairo_stroke(cr);
  }
  // The walls cut by the plane y = axis_y (vertical axes only).
  const double t = run.time_s;
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 2.0);
  for (const Wall& w : run.settings.walls) {
    if (!w.active(t)) continue;
    const Vec3 shift = w.offset(t);
    const double cx = w.point[0] + shift[0], cz = w.point[2] + shift[2];
    const bool vertical = std::abs(w.normal[2]) > 0.999;
    if (w.kind == WallKind::kCylinder && vertical) {
      const double z0 = cz + std::max(w.axial_min, -1e3), z1 = cz + std::min(w.axial_max, 1e3);
      for (double side : {-1.0, 1.0}) {
        canvas.line(f.px(cx + side * w.radius), f.py(z0), f.px(cx + side * w.radius), f.py(z1));
      }
    } else if (w.kind == WallKind::kCone && vertical) {
      const double up = w.normal[2] > 0 ? 1.0 : -1.0, tan_a = std::tan(w.half_angle_rad);
      const double s0 = std::max(w.axial_min, 0.0), s1 = std::min(w.axial_max, 1e3);
      for (double side : {-1.0, 1.0}) {
        canvas.line(f.px(cx + side * s0 * tan_a), f.py(cz + up * s0), f.px(cx + side * s1 * tan_a),
                    f.py(cz + up * s1));
      }
    } else if (w.kind == WallKind::kOrificePlate && vertical) {
      canvas.line(f.px(view_.x_lo), f.py(cz), f.px(cx - w.radius), f.py(cz));
      canvas.line(f.px(cx + w.radius), f.py(cz), f.px(view_.x_hi), f.py(cz));
    } else if (w.kind == WallKind::kPlane && vertical) {
      const double dash = 6.0;
      cairo_set_dash(cr, &dash, 1, 0);
      canvas.line(f.px(view_.x_lo), f.py(cz), f.px(view_.x_hi), f.py(cz));
      cairo_set_dash(cr, nullptr, 0, 0);
    }
  }
  cairo_restore(cr);
  draw_axes(canvas, f, 1e3, "x [mm]", "z [mm]");
  // Title: time, particles, what is drawn.
  cairo_set_source_rgb(cr, 0, 0, 0);
  canvas.text(
      kLeft, 24,
      fmt::format("t = {:.4f} s   {} particles ({} removed)   slab |y - {:.4g}| < {:.3g} mm", t,
                  p.size(), run.removed_count, view_.axis_y, view_.slab_half_width * 1e3));
  // Legend: one swatch per initial-height band, the top band first.
  const double lx = f.px1 + 20;
  canvas.text(lx, f.py0 + 12, "initial height");
  for (int layer = view_.layers - 1, row = 0; layer >= 0; --layer, ++row) {
    const Rgb c = layer_colour(layer);
    const double y = f.py0 + 24 + 20 * row;
    cairo_rectangle(cr, lx, y, 16, 14);
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    const std::string label = layer == view_.layers - 1 ? fmt::format("band {} (top)", layer + 1)
                              : layer == 0              ? std::string("band 1 (bottom)")
                                                        : fmt::format("band {}", layer + 1);
    canvas.text(lx + 22, y + 12, label);
  }
  canvas.save(frame_path(frame));
}

void write_discharge_plot(const std::string& path, const std::vector<DischargeRow>& rows,
                          const std::string& title) {
  constexpr int kWidth = 800, kHeight = 500;
  Canvas canvas(kWidth, kHeight);
  cairo_t* cr = canvas.cr();
  double t0 = 0.0, t1 = 1e-9, m1 = 1e-12;
  if (!rows.empty()) {
    t0 = rows.front().time_s;
    t1 = std::max(rows.back().time_s, t0 + 1e-9);
  }
  for (const DischargeRow& r : rows) m1 = std::max(m1, r.discharged_kg);
  const Frame f{kLeft + 20.0, kWidth - 30.0, kTop,     kHeight - static_cast<double>(kBottom), t0,
                t1,           0.0,           1.05 * m1};
  draw_axes(canvas, f, 1.0, "time [s]", "discharged mass [kg]");
  cairo_set_source_rgb(cr, 0, 0, 0);
  canvas.text(f.px0, 24, title);
  cairo_set_source_rgb(cr, 0.122, 0.467, 0.706);
  cairo_set_line_width(cr, 2.0);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double x = f.px(rows[k].time_s), y = f.py(rows[k].discharged_kg);
    k == 0 ? cairo_move_to(cr, x, y) : cairo_line_to(cr, x, y);
  }
  cairo_stroke(cr);
  canvas.save(path);
}

}  // namespace contactlab::dem
