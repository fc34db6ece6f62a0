#include "texture.hpp"

#include "hash.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rgbl::sim_detail {
namespace {

Rgb operator*(Rgb c, float k) { return {c.r * k, c.g * k, c.b * k}; }
Rgb operator+(Rgb a, Rgb b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
Rgb mix(Rgb a, Rgb b, float w) { return {a.r + (b.r - a.r) * w, a.g + (b.g - a.g) * w, a.b + (b.b - a.b) * w}; }
Rgb grey(float g) { return {g, g, g}; }

// How much of a feature of `size` metres survives at a sample footprint of `footprint` metres:
// 1 when it spans two footprints or more, 0 when it is no larger than one.
float lod(double size, double footprint) {
  return static_cast<float>(std::clamp(size / footprint - 1.0, 0.0, 1.0));
}

float smooth(float t) { return t * t * (3.0F - 2.0F * t); }

// floor() without a libm call (baseline x86-64 has no rounding instruction); |x| < 2^31.
double fast_floor(double x) {
  const auto i = static_cast<double>(static_cast<std::int64_t>(x));
  return i > x ? i - 1.0 : i;
}

std::int32_t cell_of(double x) { return static_cast<std::int32_t>(fast_floor(x)); }

// Value noise in [0, 1] on a lattice of 1 / inv_cell metres.
float value_noise(double u, double v, double inv_cell, std::uint32_t salt) {
  const double x = u * inv_cell, y = v * inv_cell;
  const double fx = fast_floor(x), fy = fast_floor(y);
  const auto ix = static_cast<std::int32_t>(fx), iy = static_cast<std::int32_t>(fy);
  const float tx = smooth(static_cast<float>(x - fx)), ty = smooth(static_cast<float>(y - fy));
  const std::uint32_t r0 = hash32(static_cast<std::uint32_t>(iy) + salt * 0x85EBCA77U);
  const std::uint32_t r1 = hash32(static_cast<std::uint32_t>(iy) + 1U + salt * 0x85EBCA77U);
  const std::uint32_t xa = static_cast<std::uint32_t>(ix) * 0x9E3779B1U, xb = xa + 0x9E3779B1U;
  const float a = unit(hash32(xa ^ r0)), b = unit(hash32(xb ^ r0));
  const float c = unit(hash32(xa ^ r1)), d = unit(hash32(xb ^ r1));
  return a + (b - a) * tx + (c - a) * ty + (a - b - c + d) * tx * ty;
}

// Zero-mean fractal noise in about [-1, 1]: `octaves` lattices from `cell` down by halves, each faded
// out once it gets finer than the footprint.
float fbm(double u, double v, double cell, int octaves, std::uint32_t salt, double footprint) {
  float sum = 0.0F, amp = 1.0F, norm = 0.0F;
  for (int o = 0; o < octaves; ++o) {
    norm += amp;
    const float w = lod(cell, footprint);
    if (w > 0.0F) {
      sum += amp * w * (2.0F * value_noise(u, v, 1.0 / cell, salt + static_cast<std::uint32_t>(o) * 7919U) - 1.0F);
    }
    amp *= 0.6F;
    cell *= 0.4;
  }
  return sum / norm;
}

// A sparse layer of hard-edged rectangles: each cell of a `cell`-metre grid holds one with
// probability `density`, of random size and place inside the cell. weight is the rectangle's LOD
// weight (0 outside any), id its hash (for its colour).
struct RectHit {
  float weight = 0.0F;
  std::uint32_t id = 0;
  float value() const { return weight * (2.0F * unit(id) - 1.0F); }  // signed, in [-1, 1]
};

RectHit rects(double u, double v, double cell, float density, std::uint32_t salt, double footprint) {
  const std::int32_t ix = cell_of(u / cell), iy = cell_of(v / cell);
  const std::uint32_t h = hash32(static_cast<std::uint32_t>(ix) * 0x9E3779B1U ^ static_cast<std::uint32_t>(iy) * 0x85EBCA77U ^
                                 salt * 0xC2B2AE3DU);
  if (unit(h) >= density) return {};
  // Further draws by a multiplicative congruential step: unit() reads the well-mixed high bits.
  const std::uint32_t h1 = hash32(h ^ 0x68E31DA4U), h2 = h1 * 0x2C1B3C6DU + 0x297A2D39U;
  const std::uint32_t h3 = h2 * 0x2C1B3C6DU + 0x297A2D39U, h4 = h3 * 0x2C1B3C6DU + 0x297A2D39U;
  const double w = cell * (0.25 + 0.7 * unit(h1)), ht = cell * (0.25 + 0.7 * unit(h2));
  const double x0 = ix * cell + (cell - w) * unit(h3), y0 = iy * cell + (cell - ht) * unit(h4);
  if (u < x0 || u >= x0 + w || v < y0 || v >= y0 + ht) return {};
  return {lod(std::min(w, ht), footprint), hash32(h4)};
}

// Inside [x0, x1] x [y0, y1]?
bool inside(double u, double v, double x0, double x1, double y0, double y1) { return u >= x0 && u < x1 && v >= y0 && v < y1; }

constexpr Rgb kFacadePalette[] = {{0.78F, 0.72F, 0.62F}, {0.62F, 0.36F, 0.28F}, {0.70F, 0.70F, 0.68F},
                                  {0.88F, 0.86F, 0.80F}, {0.80F, 0.68F, 0.45F}, {0.55F, 0.60F, 0.66F},
                                  {0.47F, 0.44F, 0.42F}, {0.76F, 0.56F, 0.52F}};
constexpr Rgb kBright[] = {{0.90F, 0.15F, 0.12F}, {0.10F, 0.35F, 0.85F}, {0.95F, 0.80F, 0.10F}, {0.10F, 0.65F, 0.25F},
                           {0.95F, 0.95F, 0.92F}, {0.08F, 0.08F, 0.10F}, {0.85F, 0.40F, 0.75F}, {0.95F, 0.55F, 0.10F},
                           {0.20F, 0.75F, 0.85F}, {0.45F, 0.20F, 0.60F}};
constexpr Rgb kCarPalette[] = {{0.85F, 0.85F, 0.84F}, {0.07F, 0.07F, 0.08F}, {0.58F, 0.60F, 0.62F}, {0.62F, 0.08F, 0.07F},
                               {0.10F, 0.20F, 0.50F}, {0.12F, 0.30F, 0.18F}, {0.32F, 0.33F, 0.35F}, {0.85F, 0.70F, 0.10F}};
constexpr Rgb kContainerPalette[] = {{0.55F, 0.15F, 0.10F}, {0.10F, 0.25F, 0.55F}, {0.12F, 0.40F, 0.22F},
                                     {0.80F, 0.45F, 0.10F}, {0.50F, 0.50F, 0.50F}, {0.40F, 0.12F, 0.15F}};

template <std::size_t N>
Rgb pick(const Rgb (&palette)[N], std::uint32_t h) {
  return palette[h % N];
}

Rgb road(const SurfacePoint& s, double fp) {
  float g = 0.31F + 0.07F * fbm(s.u, s.v, 3.0, 6, 11U, fp);
  g += 0.07F * rects(s.u, s.v, 2.7, 0.35F, 12U, fp).value();         // repair patches
  g += 0.10F * rects(s.u + 0.37, s.v + 1.1, 0.8, 0.3F, 13U, fp).value();  // stains
  g += 0.16F * rects(s.u, s.v, 0.23, 0.25F, 14U, fp).value();         // chips and gravel
  g += 0.14F * rects(s.u + 0.05, s.v + 0.11, 0.13, 0.2F, 15U, fp).value();
  return {g * 1.01F, g, g * 0.96F};
}

Rgb marking(const SurfacePoint& s, double fp) {
  float g = 0.80F + 0.05F * fbm(s.u, s.v, 0.5, 4, 21U, fp);
  g -= 0.28F * rects(s.u, s.v, 0.45, 0.35F, 22U, fp).weight;  // worn paint
  return {g, g, g * 0.97F};
}

Rgb sidewalk(const SurfacePoint& s, double fp) {
  constexpr double kTile = 0.45;
  const double x = s.u / kTile, y = s.v / kTile;
  const std::int32_t tx = cell_of(x), ty = cell_of(y);
  const std::uint32_t h = hash2(tx, ty, 31U);
  const float wt = lod(kTile, fp);
  float g = 0.52F + wt * 0.2F * (2.0F * unit(h) - 1.0F);
  Rgb tint = {1.0F, 0.97F, 0.92F};
  if (unit(hash32(h)) < 0.12F) tint = mix(tint, Rgb{1.15F, 0.78F, 0.68F}, wt);  // reddish pavers
  const double e = std::min({x - tx, tx + 1.0 - x, y - ty, ty + 1.0 - y}) * kTile;
  if (e < 0.012) g = g + (0.30F - g) * lod(0.03, fp);  // joints
  g += 0.05F * fbm(s.u, s.v, 1.0, 4, 32U, fp);
  g += 0.06F * rects(s.u, s.v, 1.3, 0.25F, 33U, fp).value();
  return tint * g;
}

Rgb poster(double u, double v, std::uint32_t h, double fp) {
  Rgb c = pick(kBright, h);
  const RectHit big = rects(u, v, 0.5, 0.6F, h + 1U, fp);
  if (big.weight > 0.0F) c = mix(c, pick(kBright, big.id), big.weight);
  const float blob = value_noise(u, v, 1.0 / 0.3, h + 2U);
  if (blob > 0.62F) c = mix(c, pick(kBright, h >> 8U), lod(0.3, fp));
  const RectHit small = rects(u + 0.13, v + 0.07, 0.2, 0.5F, h + 3U, fp);
  if (small.weight > 0.0F) c = mix(c, pick(kBright, small.id), small.weight);
  const RectHit text = rects(u, v, 0.07, 0.45F, h + 4U, fp);
  if (text.weight > 0.0F) c = mix(c, unit(text.id) < 0.5F ? grey(0.05F) : grey(0.95F), text.weight);
  return c;
}

// A building's look, drawn from its seed.
struct FacadeStyle {
  std::uint32_t seed = 0;
  Rgb base, frame;
  double floor_h = 0.0, bay_w = 0.0, win_w = 0.0, win_h = 0.0, sill = 0.0, ground_h = 0.0;
  bool brick = false;
};

FacadeStyle make_style(std::uint32_t seed) {
  const std::uint32_t b = hash32(seed);
  FacadeStyle st;
  st.seed = seed;
  st.base = pick(kFacadePalette, b);
  st.floor_h = 2.8 + 0.6 * unit(hash32(b + 1U));
  st.bay_w = 2.0 + 1.6 * unit(hash32(b + 2U));
  st.win_w = st.bay_w * (0.38 + 0.22 * unit(hash32(b + 3U)));
  st.win_h = st.floor_h * (0.42 + 0.2 * unit(hash32(b + 4U)));
  st.sill = st.floor_h * 0.28;
  st.ground_h = st.floor_h * (1.05 + 0.3 * unit(hash32(b + 5U)));
  st.brick = unit(hash32(b + 6U)) < 0.4F;
  st.frame = unit(hash32(b + 7U)) < 0.6F ? grey(0.9F) : Rgb{0.30F, 0.20F, 0.12F};
  return st;
}

Rgb facade(const SurfacePoint& s, double fp) {
  // Neighbouring samples mostly see the same building: keep its style at hand.
  thread_local FacadeStyle cached = make_style(0);
  if (cached.seed != s.seed) cached = make_style(s.seed);
  const FacadeStyle& st = cached;
  const std::uint32_t salt = hash32(s.seed + s.face);
  const Rgb base = st.base, frame = st.frame;
  const double floor_h = st.floor_h, bay_w = st.bay_w, win_w = st.win_w, win_h = st.win_h, sill = st.sill;
  const double ground_h = st.ground_h;
  const bool brick = st.brick;
  const double u = s.u, v = s.v;

  // The wall: large-scale noise, bricks or plaster, stains, a cornice at every floor.
  float k = 0.9F + 0.10F * fbm(u, v, 2.0, 5, salt, fp);
  if (brick) {
    constexpr double kBh = 0.075, kBw = 0.25;
    const std::int32_t row = cell_of(v / kBh);
    const double shifted = u + ((row & 1) != 0 ? 0.5 * kBw : 0.0);
    const std::int32_t col = cell_of(shifted / kBw);
    k += 0.10F * lod(kBh, fp) * (2.0F * unit(hash2(col, row, salt + 1U)) - 1.0F);
    const double ex = std::min(shifted / kBw - col, col + 1.0 - shifted / kBw) * kBw;
    const double ey = std::min(v / kBh - row, row + 1.0 - v / kBh) * kBh;
    if (std::min(ex, ey) < 0.008) k += (1.15F - k) * lod(0.02, fp);
  }
  k *= 1.0F + 0.2F * rects(u, v, 1.6, 0.3F, salt + 2U, fp).value();   // weathering
  k *= 1.0F + 0.3F * rects(u, v, 0.55, 0.22F, salt + 9U, fp).value();  // plaques, vents, dirt
  Rgb c = base * k;
  if (v >= ground_h && v - ground_h - floor_h * fast_floor((v - ground_h) / floor_h) < 0.18) c = mix(c, base * 1.18F, lod(0.18, fp));
  if (v < 0.3) c = mix(c, base * 0.6F, lod(0.3, fp));  // plinth

  if (v < ground_h) {  // shops, posters, doors, graffiti
    const double bw = bay_w * 1.5;
    const std::int32_t bay = cell_of(u / bw);
    const double lu = u - bay * bw;
    const std::uint32_t h = hash2(bay, 0, salt + 3U);
    const double top = std::min(2.6, ground_h - 0.3);
    switch (h % 4U) {
      case 0:  // poster with a white border
        if (inside(lu, v, 0.25, bw - 0.25, 0.4, top)) {
          const Rgb p = inside(lu, v, 0.3, bw - 0.3, 0.45, top - 0.05) ? poster(lu, v, h, fp) : grey(0.95F);
          c = mix(c, p, lod(0.5, fp));
        }
        break;
      case 1:  // shop window
        if (inside(lu, v, 0.2, bw - 0.2, 0.5, ground_h - 0.35)) {
          Rgb g = inside(lu, v, 0.26, bw - 0.26, 0.56, ground_h - 0.41) ? Rgb{0.10F, 0.12F, 0.15F} : frame;
          const RectHit goods = rects(lu, v, 0.35, 0.55F, h + 5U, fp);
          if (goods.weight > 0.0F && inside(lu, v, 0.26, bw - 0.26, 0.56, ground_h - 0.41))
            g = mix(g, pick(kBright, goods.id) * 0.7F, goods.weight);
          c = mix(c, g, lod(0.5, fp));
        }
        break;
      case 2:  // door
        if (inside(lu, v, 0.5 * bw - 0.55, 0.5 * bw + 0.55, 0.0, 2.2)) {
          Rgb d = Rgb{0.33F, 0.21F, 0.12F} * (0.9F + 0.1F * fbm(lu, v, 0.5, 3, h, fp));
          if (inside(lu, v, 0.5 * bw + 0.35, 0.5 * bw + 0.45, 1.0, 1.08)) d = grey(0.8F);
          c = mix(c, d, lod(0.5, fp));
        }
        break;
      default: {  // graffiti and stickers
        const RectHit g = rects(lu, v, 0.45, 0.55F, h + 6U, fp);
        if (g.weight > 0.0F && v > 0.3 && v < 2.4) c = mix(c, pick(kBright, g.id), g.weight);
        break;
      }
    }
    return c;
  }

  // Upper floors: one window per bay and floor, each with its own glass, curtain and bars.
  const std::int32_t floor_i = cell_of((v - ground_h) / floor_h);
  const double lv = v - ground_h - floor_i * floor_h;
  const std::int32_t bay = cell_of(u / bay_w);
  const double lu = u - bay * bay_w;
  const double x0 = 0.5 * (bay_w - win_w), x1 = x0 + win_w, y0 = sill, y1 = sill + win_h;
  if (u < 0.4 || u > s.extent_u - 0.4 || v > s.extent_v - 0.8) return c;  // keep windows off edges and roof line
  const std::uint32_t wh = hash2(bay, floor_i, salt + 4U);
  if (unit(wh) > 0.93F) return c;  // a bricked-up window
  const float ww = lod(std::min(win_w, win_h), fp);
  if (inside(lu, lv, x0 - 0.05, x1 + 0.05, y0 - 0.08, y0)) return mix(c, grey(0.82F), lod(0.08, fp));  // sill
  if (!inside(lu, lv, x0, x1, y0, y1)) return c;
  const double f = 0.07;
  Rgb w;
  if (!inside(lu, lv, x0 + f, x1 - f, y0 + f, y1 - f)) {
    w = frame;
  } else {
    const float glass = 0.08F + 0.35F * unit(hash32(wh + 1U));
    w = Rgb{glass * 0.9F, glass * 0.95F, glass * 1.1F};
    const double curtain = (y1 - y0) * 0.85 * unit(hash32(wh + 2U));
    if (lv > y1 - f - curtain) {
      const Rgb cloth = pick(kFacadePalette, hash32(wh + 3U)) * 1.05F;
      w = cloth * (0.9F + 0.1F * fbm(lu, 0.0, 0.12, 2, wh, fp));
    }
    if (unit(hash32(wh + 4U)) < 0.6F) {  // glazing bars
      const double cx = 0.5 * (x0 + x1), cy = y0 + 0.62 * (y1 - y0);
      if (std::abs(lu - cx) < 0.03 || std::abs(lv - cy) < 0.03) w = mix(w, frame, lod(0.06, fp));
    }
  }
  return mix(c, w, ww);
}

Rgb car(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 101U);
  const Rgb paint = pick(kCarPalette, h) * (0.96F + 0.04F * fbm(s.u, s.v, 0.8, 3, h, fp));
  if (s.face == 3 || s.face == 2) return paint;
  Rgb c = paint;
  const double u = s.u, v = s.v, len = s.extent_u;
  if (v < 0.22) return mix(c, grey(0.07F), lod(0.2, fp));  // sill and tyres
  if (s.face == 4 || s.face == 5) {  // sides: wheels, door seams, handles
    for (const double wc : {0.85, len - 0.85}) {
      if (std::abs(u - wc) < 0.38 && v < 0.62) return mix(c, grey(0.05F), lod(0.3, fp));
    }
    const double seam = 0.5 * len + (unit(hash32(h + 1U)) - 0.5) * 0.3;
    if (std::abs(u - seam) < 0.012 && v > 0.25) c = mix(c, paint * 0.5F, lod(0.03, fp));
    if (std::abs(u - seam - 0.45) < 0.1 && std::abs(v - (s.extent_v - 0.22)) < 0.025) c = mix(c, grey(0.15F), lod(0.05, fp));
    return c;
  }
  // Front (face 0) and back (face 1): plate, lights, grille.
  const double w = s.extent_u, mid = 0.5 * w;
  if (inside(u, v, mid - 0.26, mid + 0.26, 0.32, 0.44)) {
    Rgb plate = grey(0.92F);
    const RectHit ch = rects(u, v, 0.045, 0.6F, h + 2U, fp);
    if (ch.weight > 0.0F && inside(u, v, mid - 0.23, mid + 0.23, 0.34, 0.42)) plate = mix(plate, grey(0.1F), ch.weight);
    return mix(c, plate, lod(0.12, fp));
  }
  const Rgb light = s.face == 0 ? Rgb{0.95F, 0.92F, 0.75F} : Rgb{0.75F, 0.05F, 0.05F};
  if ((u < 0.35 || u > w - 0.35) && v > s.extent_v - 0.28 && v < s.extent_v - 0.1) return mix(c, light, lod(0.15, fp));
  if (s.face == 0 && inside(u, v, mid - 0.45, mid + 0.45, 0.48, s.extent_v - 0.12)) return mix(c, grey(0.1F), lod(0.2, fp));
  return c;
}

Rgb cabin(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 101U);  // same paint as the body
  const Rgb paint = pick(kCarPalette, h);
  if (s.face == 3 || s.face == 2) return paint;
  const double u = s.u, v = s.v, w = s.extent_u, bottom = s.extent_v - 0.5;
  const double pillar = 0.1;
  bool glass = u > pillar && u < w - pillar && v > s.extent_v - 0.45 && v < s.extent_v - 0.07 && v > bottom;
  if ((s.face == 4 || s.face == 5) && std::abs(u - 0.5 * w) < 0.06) glass = false;  // B pillar
  if (!glass) return paint;
  const float g = 0.06F + 0.18F * unit(hash32(h + static_cast<std::uint32_t>(s.face)));
  const Rgb pane = Rgb{g, g * 1.05F, g * 1.15F} + grey(0.05F * fbm(u, v, 0.4, 2, h, fp));
  return mix(paint, pane, lod(0.1, fp));
}

Rgb container(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 202U);
  const Rgb paint = pick(kContainerPalette, h);
  float k = 0.92F + 0.08F * fbm(s.u, s.v, 1.0, 5, h, fp);
  if (s.face != 2 && s.face != 3) {
    const double rib = s.u / 0.28 - fast_floor(s.u / 0.28);
    if (rib < 0.4) k *= 1.0F + 0.18F * lod(0.1, fp);
  }
  k *= 1.0F + 0.25F * rects(s.u, s.v, 0.4, 0.3F, h + 3U, fp).value();  // dents and stickers
  Rgb c = paint * k;
  const RectHit rust = rects(s.u, s.v, 0.9, 0.4F, h + 1U, fp);
  if (rust.weight > 0.0F) c = mix(c, Rgb{0.35F, 0.18F, 0.08F}, 0.7F * rust.weight);
  if (s.face != 2 && s.face != 3 && inside(s.u, s.v, 0.3, 1.6, s.extent_v - 0.9, s.extent_v - 0.3)) {  // label
    Rgb label = grey(0.92F);
    const RectHit t = rects(s.u, s.v, 0.09, 0.5F, h + 2U, fp);
    if (t.weight > 0.0F) label = mix(label, grey(0.08F), t.weight);
    c = mix(c, label, lod(0.3, fp));
  }
  return c;
}

Rgb pole(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 303U);
  Rgb c = grey(0.50F + 0.10F * unit(h)) * (0.92F + 0.08F * fbm(s.u * 4.0, s.v, 0.6, 4, h, fp));
  if (s.face == 1) return c;
  if (unit(hash32(h + 1U)) < 0.5F) {  // reflective bands
    const double band = s.v - 1.4;
    if (band > 0.0 && band < 0.6) c = mix(c, (static_cast<int>(band / 0.15) % 2) != 0 ? grey(0.92F) : Rgb{0.8F, 0.1F, 0.1F}, lod(0.15, fp));
  }
  if (s.v < 2.6) {
    const RectHit sticker = rects(s.u, s.v, 0.16, 0.4F, h + 2U, fp);
    if (sticker.weight > 0.0F) c = mix(c, pick(kBright, sticker.id), sticker.weight);
  }
  return c;
}

Rgb sign(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 404U);
  if (s.face != 0 && s.face != 1) return grey(0.55F);
  if (s.face == 0) return grey(0.6F);  // the back
  const double u = s.u, v = s.v - (s.extent_v - 0.7);
  const Rgb field = pick(kBright, h);
  if (u < 0.05 || u > s.extent_u - 0.05 || v < 0.05 || v > 0.65) return mix(field, grey(0.95F), lod(0.05, fp));
  Rgb c = field;
  const RectHit symbol = rects(u, v, 0.2, 0.7F, h + 1U, fp);
  if (symbol.weight > 0.0F) c = mix(c, unit(symbol.id) < 0.5F ? grey(0.05F) : grey(0.95F), symbol.weight);
  return c;
}

Rgb bark(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 505U);
  float k = 0.9F + 0.15F * fbm(s.u * 3.0, s.v, 0.5, 4, h, fp);
  k *= 1.0F + 0.35F * rects(s.u, s.v, 0.09, 0.35F, h + 1U, fp).value();
  return Rgb{0.30F, 0.22F, 0.15F} * k;
}

// Leaf clusters: dark gaps and lit clumps on two scales, hard-edged (many corners, like real trees).
Rgb foliage(const SurfacePoint& s, double fp) {
  const std::uint32_t h = hash32(s.seed + 606U);
  const Rgb leaf = unit(h) < 0.5F ? Rgb{0.20F, 0.36F, 0.12F} : Rgb{0.26F, 0.38F, 0.10F};
  float k = 0.85F + 0.25F * fbm(s.u, s.v, 0.8, 4, h, fp);
  k *= 1.0F + 0.55F * rects(s.u, s.v, 0.3, 0.5F, h + 1U, fp).value();
  k *= 1.0F + 0.45F * rects(s.u + 0.07, s.v + 0.05, 0.12, 0.45F, h + 2U, fp).value();
  return leaf * k;
}

}  // namespace

Rgb albedo(const SurfacePoint& s, double footprint) {
  switch (s.kind) {
    case SurfaceKind::road: return road(s, footprint);
    case SurfaceKind::marking: return marking(s, footprint);
    case SurfaceKind::sidewalk: return sidewalk(s, footprint);
    case SurfaceKind::facade: return facade(s, footprint);
    case SurfaceKind::car: return car(s, footprint);
    case SurfaceKind::cabin: return cabin(s, footprint);
    case SurfaceKind::container: return container(s, footprint);
    case SurfaceKind::pole: return pole(s, footprint);
    case SurfaceKind::sign: return sign(s, footprint);
    case SurfaceKind::bark: return bark(s, footprint);
    case SurfaceKind::foliage: return foliage(s, footprint);
  }
  return grey(0.5F);
}

bool leaf_gap(const Eigen::Vector3d& p, double share) {
  // two lattices on slanted planes so that the blobs are not aligned with the street
  const float n = 0.65F * value_noise(p.x() + 0.6 * p.y(), p.z() - 0.4 * p.y(), 1.0 / 0.45, 707U) +
                  0.35F * value_noise(p.x() - 0.3 * p.y(), p.z() + 0.7 * p.y(), 1.0 / 0.17, 708U);
  // two octaves of value noise cluster around 0.5: a linear map of the share onto the threshold is
  // close enough (measured: 0.2, 0.35, 0.5 give about 21, 34, 49 % of gaps)
  const float threshold = 0.5F + 0.45F * (0.5F - static_cast<float>(std::clamp(share, 0.0, 1.0)));
  return n > threshold;
}

}  // namespace rgbl::sim_detail
