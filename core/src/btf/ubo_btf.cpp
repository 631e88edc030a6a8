#include "prtlab/btf/ubo_btf.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/atomic_file.h"

namespace prt {
namespace fs = std::filesystem;

namespace {

constexpr double kDrrEps = 1e-5;  // btflib's default drr_eps; not stored in the files
constexpr std::size_t kMetaStringBytes = 80;

struct Signature {
  std::string_view text, format;
};
constexpr std::array<Signature, 5> kSignatures = {{{"!DFMF08FCR", "DFMF"},
                                                   {"!FMF12FCER", "FMF"},
                                                   {"!FMF06FCR", "FMF"},
                                                   {"!FMF06FC", "FMF"},
                                                   {"!BDIF06R2!", "BDI"}}};

template <class T>
T from_le(T v) {
  if constexpr (std::endian::native == std::endian::big) {
    auto bytes = std::bit_cast<std::array<unsigned char, sizeof(T)>>(v);
    std::reverse(bytes.begin(), bytes.end());
    return std::bit_cast<T>(bytes);
  }
  return v;
}

// Sequential little-endian reads that never run past the end of the file: every request is
// checked against the bytes left before anything is allocated for it.
class ByteReader {
 public:
  explicit ByteReader(const fs::path& file) : file_(file) {
    std::error_code ec;
    if (!fs::exists(file, ec)) throw InputError(file, "file not found");
    if (!fs::is_regular_file(file, ec)) throw InputError(file, "not a regular file");
    size_ = fs::file_size(file, ec);
    if (ec) throw InputError(file, fmt::format("cannot read: {}", ec.message()));
    in_.open(file, std::ios::binary);
    if (!in_) throw InputError(file, "cannot open for reading");
  }
  const fs::path& file() const { return file_; }
  std::uint64_t pos() const { return pos_; }
  std::uint64_t remaining() const { return size_ - pos_; }

  // count * each bytes, refused (without overflow) when more than what is left.
  void need(std::uint64_t count, std::uint64_t each, std::string_view what) const {
    if (each != 0 && count > remaining() / each)
      throw InputError(file_, fmt::format("truncated: {} needs {} x {} bytes at offset {}, the "
                                          "file has {} left",
                                          what, count, each, pos_, remaining()));
  }
  void read(void* dst, std::uint64_t n, std::string_view what) {
    need(n, 1, what);
    in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (!in_) throw InputError(file_, fmt::format("read failed at offset {} ({})", pos_, what));
    pos_ += n;
  }
  void seek(std::uint64_t offset) {
    PRT_CHECK(offset <= size_, "seek to {} past the end {}", offset, size_);
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    if (!in_) throw InputError(file_, fmt::format("seek to offset {} failed", offset));
    pos_ = offset;
  }
  void skip(std::uint64_t count, std::uint64_t each, std::string_view what) {
    need(count, each, what);
    in_.seekg(static_cast<std::streamoff>(count * each), std::ios::cur);
    if (!in_) throw InputError(file_, fmt::format("seek failed at offset {} ({})", pos_, what));
    pos_ += count * each;
  }
  template <class T>
  T get(std::string_view what) {
    T v;
    read(&v, sizeof(T), what);
    return from_le(v);
  }
  std::uint32_t u32(std::string_view what) { return get<std::uint32_t>(what); }
  float f32(std::string_view what) { return std::bit_cast<float>(u32(what)); }

  // `count` scalars of `bytes` (2 half, 4 f32, 8 f64) as float.
  std::vector<float> scalars(std::uint64_t count, int bytes, std::string_view what) {
    need(count, static_cast<std::uint64_t>(bytes), what);
    std::vector<float> out(static_cast<std::size_t>(count));
    if (bytes == 2) {
      std::vector<std::uint16_t> raw(out.size());
      read(raw.data(), count * 2, what);
      for (std::size_t i = 0; i < out.size(); ++i) out[i] = half_to_float(from_le(raw[i]));
    } else if (bytes == 4) {
      read(out.data(), count * 4, what);
      for (float& f : out) f = from_le(f);
    } else {
      std::vector<double> raw(out.size());
      read(raw.data(), count * 8, what);
      for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<float>(from_le(raw[i]));
    }
    return out;
  }

 private:
  fs::path file_;
  std::ifstream in_;
  std::uint64_t size_ = 0, pos_ = 0;
};

class ByteWriter {
 public:
  template <class T>
  void put(T v) {
    v = from_le(v);
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void u8(std::uint8_t v) { put(v); }
  void u32(std::uint64_t v) {
    if (v > std::numeric_limits<std::uint32_t>::max())
      throw ParameterError(fmt::format("{} does not fit the format's 32-bit field", v));
    put(static_cast<std::uint32_t>(v));
  }
  void f32(double v) { put(static_cast<float>(v)); }
  void text(std::string_view s) {
    const auto* p = reinterpret_cast<const std::byte*>(s.data());
    bytes_.insert(bytes_.end(), p, p + s.size());
  }
  void zeros(std::size_t n) { bytes_.insert(bytes_.end(), n, std::byte{0}); }
  void scalar(float v, int bytes) {
    if (bytes == 2)
      put(float_to_half(v));
    else
      put(v);
  }
  const std::vector<std::byte>& bytes() const { return bytes_; }

 private:
  std::vector<std::byte> bytes_;
};

struct Header {
  std::string signature, format;
  int channels = 3;
  bool cosine_flag = false;
  std::array<float, 3> rgb_scale{1, 1, 1};
  std::vector<Vec3d> views, lights;
  std::uint32_t width = 0, height = 0;
  std::uint64_t texels() const { return static_cast<std::uint64_t>(width) * height; }
};

std::string read_signature(ByteReader& r) {
  std::array<char, 10> buf{};
  const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(10, r.remaining()));
  r.read(buf.data(), n, "signature");
  const std::string_view got(buf.data(), n);
  const Signature* best = nullptr;
  for (const Signature& s : kSignatures)
    if (got.substr(0, s.text.size()) == s.text && (!best || s.text.size() > best->text.size()))
      best = &s;
  if (!best) {
    std::string shown;
    for (char c : got) shown += (c >= 32 && c < 127) ? c : '?';
    throw InputError(r.file(), fmt::format("not a Bonn BTF: signature '{}' is none of !DFMF08FCR, "
                                           "!FMF12FCER, !FMF06FCR, !FMF06FC, !BDIF06R2!",
                                           shown));
  }
  r.seek(best->text.size());
  return std::string(best->text);
}

void read_meta(ByteReader& r, Header& h) {
  const std::uint64_t start = r.pos();
  const std::uint32_t size = r.u32("meta data size");
  const std::uint32_t version = r.u32("meta data version");
  if (version < 1 || version > 4)
    throw InputError(r.file(), fmt::format("meta data version {} is not 1..4", version));
  r.skip(3 * kMetaStringBytes, 1, "meta data strings");
  r.f32("pixels per mm");
  for (float& s : h.rgb_scale) s = r.f32("RGB scale factor");
  if (version > 1) h.cosine_flag = r.u32("cosine flag") != 0;
  if (version > 2) r.skip(r.u32("XML size"), 1, "XML");
  if (version > 3) {
    const std::uint32_t channels = r.u32("channel count");
    r.need(channels, 4, "channel names");
    for (std::uint32_t c = 0; c < channels; ++c) r.skip(r.u32("channel name size"), 1, "name");
    if (channels != 3)
      throw InputError(r.file(),
                       fmt::format("{} colour channels; only RGB (3) is supported", channels));
    h.channels = 3;
  }
  if (r.pos() - start != size)
    throw InputError(r.file(), fmt::format("meta data block says {} bytes, its fields take {}",
                                           size, r.pos() - start));
}

Vec3d read_direction(ByteReader& r, std::string_view what) {
  const double theta = r.f32(what), phi = r.f32(what);
  if (!std::isfinite(theta) || !std::isfinite(phi))
    throw InputError(r.file(), fmt::format("non-finite {} angle at offset {}", what, r.pos()));
  return direction_from_angles(theta, phi);
}

void read_sampling(ByteReader& r, Header& h) {
  const std::uint32_t views = r.u32("view count");
  if (views == 0) throw InputError(r.file(), "no view directions");
  r.need(views, 12, "view directions");
  for (std::uint32_t v = 0; v < views; ++v) {
    h.views.push_back(read_direction(r, "view"));
    const std::uint32_t lights = r.u32("light count");
    if (v == 0) {
      if (lights == 0) throw InputError(r.file(), "no light directions");
      r.need(lights, 8, "light directions");
      for (std::uint32_t l = 0; l < lights; ++l) h.lights.push_back(read_direction(r, "light"));
    } else {
      if (lights != h.lights.size())
        throw InputError(r.file(), fmt::format("view {} lists {} lights, view 0 lists {}; only "
                                               "one light set for all views is supported",
                                               v, lights, h.lights.size()));
      r.skip(lights, 8, "light directions");
    }
  }
}

Header read_common(ByteReader& r) {
  Header h;
  h.signature = read_signature(r);
  for (const Signature& s : kSignatures)
    if (s.text == h.signature) h.format = std::string(s.format);
  read_meta(r, h);
  read_sampling(r, h);
  h.width = r.u32("width");
  h.height = r.u32("height");
  if (h.width == 0 || h.height == 0 || h.width > 65536 || h.height > 65536)
    throw InputError(r.file(), fmt::format("unsupported texture size {} x {}", h.width, h.height));
  return h;
}

void skip_rotations(ByteReader& r) {
  r.skip(r.u32("rotation count"), 9 * 4, "rotations");
}

int read_scalar_size(ByteReader& r) {
  const int bytes = r.get<std::uint8_t>("scalar size");
  if (bytes != 2 && bytes != 4 && bytes != 8)
    throw InputError(r.file(), fmt::format("scalar size {} is not 2, 4 or 8 bytes", bytes));
  return bytes;
}

// One factorised matrix: value(r, s) = sum_k U[r][k] SxV[s][k].
struct Factor {
  std::uint32_t components = 0, rows = 0, cols = 0;
  std::vector<float> s, u, sxv;
  double value(std::size_t row, std::size_t col) const {
    const float* a = u.data() + row * components;
    const float* b = sxv.data() + col * components;
    double sum = 0;
    for (std::uint32_t k = 0; k < components; ++k)
      sum += static_cast<double>(a[k]) * static_cast<double>(b[k]);
    return sum;
  }
};

Factor read_factor(ByteReader& r, int scalar_bytes, std::string_view what) {
  Factor f;
  f.components = r.u32("component count");
  f.rows = r.u32("row count");
  f.cols = r.u32("column count");
  if (f.components == 0) throw InputError(r.file(), fmt::format("{} has no components", what));
  // (1 + rows + cols) vectors of P scalars; neither factor of the check can overflow.
  r.need(1 + static_cast<std::uint64_t>(f.rows) + f.cols,
         static_cast<std::uint64_t>(f.components) * static_cast<std::uint64_t>(scalar_bytes), what);
  f.s = r.scalars(f.components, scalar_bytes, what);
  f.u = r.scalars(static_cast<std::uint64_t>(f.rows) * f.components, scalar_bytes, what);
  f.sxv = r.scalars(static_cast<std::uint64_t>(f.cols) * f.components, scalar_bytes, what);
  return f;
}

// Whether U holds the angular rows (ABRDFs; true) or the texel rows (images; false).
// `channels` is 3 for FMF (the channel is part of U's row) and 1 for a DFMF channel.
bool abrdf_rows(const ByteReader& r, const Factor& f, std::uint64_t channels, std::uint64_t angular,
                std::uint64_t texels, std::string_view what) {
  if (f.rows == channels * angular && f.cols == texels) return true;
  if (f.rows == channels * texels && f.cols == angular) return false;
  throw InputError(r.file(), fmt::format("{} matrices are {} x {} and {} x {}; this file's "
                                         "sampling needs {} x {} rows (ABRDFs x texels) or {} x "
                                         "{} (images x directions)",
                                         what, f.rows, f.components, f.cols, f.components,
                                         channels * angular, texels, channels * texels, angular));
}

// undecorrelate.m: the DFMF colour models that map to RGB.
void undecorrelate(int model, const std::array<float, 3>& mean, const std::array<float, 9>& m,
                   double v[3]) {
  auto yuv = [](double* x) {
    const double y = x[0], u = x[1], w = x[2];
    x[0] = y + 1.13983 * w;
    x[1] = y - 0.39465 * u - 0.5806 * w;
    x[2] = y + 2.03211 * u;
  };
  switch (model) {
    case 0:
      break;
    case 1:
      yuv(v);
      break;
    case 3: {
      const double x[3] = {v[0], v[1], v[2]};
      for (int i = 0; i < 3; ++i) v[i] = x[0] * m[i] + x[1] * m[3 + i] + x[2] * m[6 + i] + mean[i];
      break;
    }
    case 4: {
      const double y = v[0], co = v[1], cg = v[2];
      v[0] = y + co - cg;
      v[1] = y + cg;
      v[2] = y - co - cg;
      break;
    }
    case 9:
      v[0] = std::exp(v[0]) - kDrrEps;
      yuv(v);
      break;
    case 10:
      v[0] = std::exp(v[0]) - kDrrEps;
      for (int c = 1; c < 3; ++c)
        v[c] = (v[c] > 0   ? 1.0
                : v[c] < 0 ? -1.0
                           : 0.0) *
               std::exp(std::abs(v[c]) + std::log(kDrrEps));
      yuv(v);
      break;
    case 11:
      v[0] = std::exp(v[0]) - kDrrEps;
      v[1] *= v[0] + kDrrEps;
      v[2] *= v[0] + kDrrEps;
      yuv(v);
      break;
    case 12:
      for (int c = 0; c < 3; ++c) v[c] = std::exp(v[c]) - kDrrEps;
      break;
    default:
      PRT_CHECK(false, "colour model {} not validated", model);
  }
}

std::string lower_copy(std::string s) {
  for (char& c : s) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return s;
}

bool supported_colour_model(int model) {
  return model == 0 || model == 1 || model == 3 || model == 4 || (model >= 9 && model <= 12);
}

struct Decoded {
  Header header;
  std::function<void(int view, int light, std::span<float> tile)> tile;
  nlohmann::json parameters = nlohmann::json::object();
};

Decoded decode_fmf(ByteReader& r, Header h) {
  if (h.signature.back() == 'R') skip_rotations(r);
  std::uint32_t drr = 0;
  if (h.signature == "!FMF12FCER") {
    const int version = r.get<std::uint8_t>("FMF header version");
    if (version >= 3)
      throw InputError(r.file(), fmt::format("FMF header version {} is not 0..2", version));
    if (version >= 1) drr = r.u32("dynamic range reduction");
    if (version >= 2) {
      const std::uint32_t rows = r.u32("height map rows"), cols = r.u32("height map columns");
      r.skip(static_cast<std::uint64_t>(rows) * cols, 2, "height map");
    }
  }
  r.u32("component count");
  const int bytes = read_scalar_size(r);
  auto f = std::make_shared<Factor>(read_factor(r, bytes, "FMF"));
  const std::uint64_t nl = h.lights.size(), nc = h.channels;
  const bool by_abrdf = abrdf_rows(r, *f, nc, nl * h.views.size(), h.texels(), "FMF");
  Decoded d;
  const std::size_t texels = h.texels();
  d.tile = [f, by_abrdf, nl, nc, texels, drr](int view, int light, std::span<float> tile) {
    const std::size_t lv = light + nl * view;
    for (std::size_t t = 0; t < texels; ++t) {
      for (std::size_t c = 0; c < 3; ++c) {
        double v = by_abrdf ? f->value(c + nc * lv, t) : f->value(c + nc * t, lv);
        if (drr != 0) v = std::exp(v) - kDrrEps;
        tile[t * 3 + c] = static_cast<float>(v);
      }
    }
  };
  d.parameters = {{"components", f->components},
                  {"scalar_bytes", bytes},
                  {"dynamic_range_reduction", drr},
                  {"u_holds", by_abrdf ? "abrdfs" : "images"}};
  d.header = std::move(h);
  return d;
}

Decoded decode_dfmf(ByteReader& r, Header h) {
  skip_rotations(r);
  r.u32("component count");
  const int model = r.get<std::int32_t>("colour model");
  if (!supported_colour_model(model))
    throw InputError(r.file(), fmt::format("DFMF colour model {} is not supported (supported: 0 "
                                           "RGB, 1 YUV, 3 PCA, 4 YCoCg, 9..12 logarithmic)",
                                           model));
  std::array<float, 3> mean{};
  std::array<float, 9> matrix{};
  for (float& v : mean) v = r.f32("colour mean");
  for (float& v : matrix) v = r.f32("colour matrix");
  auto factors = std::make_shared<std::array<Factor, 3>>();
  std::array<bool, 3> by_abrdf{};
  const std::uint64_t nl = h.lights.size();
  nlohmann::json comps = nlohmann::json::array();
  for (int c = 0; c < 3; ++c) {
    const int bytes = read_scalar_size(r);
    (*factors)[c] = read_factor(r, bytes, fmt::format("DFMF channel {}", c));
    by_abrdf[c] = abrdf_rows(r, (*factors)[c], 1, nl * h.views.size(), h.texels(),
                             fmt::format("DFMF channel {}", c));
    comps.push_back((*factors)[c].components);
  }
  Decoded d;
  const std::size_t texels = h.texels();
  d.tile = [factors, by_abrdf, nl, texels, model, mean, matrix](int view, int light,
                                                                std::span<float> tile) {
    const std::size_t lv = light + nl * view;
    for (std::size_t t = 0; t < texels; ++t) {
      double v[3];
      for (int c = 0; c < 3; ++c)
        v[c] = by_abrdf[c] ? (*factors)[c].value(lv, t) : (*factors)[c].value(t, lv);
      undecorrelate(model, mean, matrix, v);
      for (int c = 0; c < 3; ++c) tile[t * 3 + c] = static_cast<float>(v[c]);
    }
  };
  d.parameters = {{"components", comps}, {"colour_model", model}};
  d.header = std::move(h);
  return d;
}

Decoded decode_bdi(ByteReader& r, Header h) {
  const std::uint32_t lines = r.u32("scan lines per chunk");
  if (lines == 0) throw InputError(r.file(), "BDI with 0 scan lines per chunk");
  const int compression = r.get<std::uint8_t>("compression");
  if (compression != 2)
    throw InputError(r.file(), fmt::format("BDI compression {} ({}) is not supported; only 2 "
                                           "(sparse uncompressed) is",
                                           compression,
                                           compression == 0   ? "full uncompressed"
                                           : compression == 1 ? "bzip2"
                                                              : "unknown"));
  const std::uint64_t texels = h.texels();
  r.need(texels, 1, "BDI mask");
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(texels));
  r.read(mask.data(), texels, "BDI mask");
  skip_rotations(r);
  const std::uint64_t stored = static_cast<std::uint64_t>(
      std::count_if(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; }));
  const std::uint64_t abrdf =
      static_cast<std::uint64_t>(h.channels) * h.lights.size() * h.views.size();
  const std::uint64_t per_chunk = static_cast<std::uint64_t>(h.width) * lines;
  // Every chunk's header and halves, checked before the texel index (8 bytes per mask byte)
  // and the buffer for them are allocated.
  const std::uint64_t chunks = (stored + per_chunk - 1) / per_chunk;
  r.need(chunks, 4, "BDI chunk headers");
  r.need(stored, abrdf * 2, "BDI chunks");
  auto storage = std::make_shared<std::vector<std::int64_t>>(mask.size(), -1);
  for (std::size_t t = 0, next = 0; t < mask.size(); ++t)
    if (mask[t]) (*storage)[t] = static_cast<std::int64_t>(next++);
  auto halves =
      std::make_shared<std::vector<std::uint16_t>>(static_cast<std::size_t>(stored * abrdf));
  for (std::uint64_t c = 0; c < chunks; ++c) {
    const std::uint64_t n = std::min(per_chunk, stored - c * per_chunk);
    const std::uint32_t bytes = r.u32("BDI chunk size");
    if (bytes != n * abrdf * 2)
      throw InputError(r.file(), fmt::format("BDI chunk {} holds {} bytes, {} texels of {} "
                                             "halves need {}",
                                             c, bytes, n, abrdf, n * abrdf * 2));
    std::uint16_t* dst = halves->data() + c * per_chunk * abrdf;
    r.read(dst, n * abrdf * 2, "BDI chunk");
    for (std::uint64_t i = 0; i < n * abrdf; ++i) dst[i] = from_le(dst[i]);
  }
  Decoded d;
  const std::size_t nl = h.lights.size();
  d.tile = [storage, halves, abrdf, nl](int view, int light, std::span<float> tile) {
    const std::size_t lv = light + nl * view;
    for (std::size_t t = 0; t < storage->size(); ++t) {
      const std::int64_t s = (*storage)[t];
      for (std::size_t c = 0; c < 3; ++c)
        tile[t * 3 + c] = s < 0 ? 0.0f : half_to_float((*halves)[s * abrdf + c + 3 * lv]);
    }
  };
  d.parameters = {{"scan_lines_per_chunk", lines}, {"stored_texels", stored}};
  d.header = std::move(h);
  return d;
}

// --- writing --------------------------------------------------------------------------------

struct GridSampling {
  std::vector<Vec2d> view_angles, light_angles;  // (theta, phi) radians
  std::vector<double> light_factor;              // b = stored * factor
};

GridSampling grid_sampling(const Btf& btf, LightCosine cosine) {
  const HemisphereGrid views(btf.view_side()), lights(btf.light_side());
  auto angles = [](const Vec3d& d) {
    return Vec2d(std::acos(std::clamp(d.z, -1.0, 1.0)), std::atan2(d.y, d.x));
  };
  GridSampling g;
  for (const Vec3d& d : views.directions()) g.view_angles.push_back(angles(d));
  for (const Vec3d& d : lights.directions()) g.light_angles.push_back(angles(d));
  const std::vector<double> projected = lights.projected_solid_angles();
  for (int l = 0; l < lights.cell_count(); ++l)
    g.light_factor.push_back(
        measured_value_factor(cosine, false, projected[l] / lights.cell_solid_angle(), 1.0));
  return g;
}

void write_common(ByteWriter& w, std::string_view signature, const Btf& btf,
                  const GridSampling& g) {
  w.text(signature);
  const std::string xml;
  const std::array<std::string_view, 3> names = {"R", "G", "B"};
  std::size_t size = 4 + 4 + 3 * kMetaStringBytes + 4 + 12 + 4 + 4 + xml.size() + 4;
  for (auto n : names) size += 4 + n.size();
  w.u32(size);
  w.u32(4);
  std::string setup = "prtlab";
  w.text(setup);
  w.zeros(kMetaStringBytes - setup.size());
  w.zeros(2 * kMetaStringBytes);
  w.f32(0.0);  // pixels per mm: unknown for a synthetic tile
  for (int c = 0; c < 3; ++c) w.f32(1.0);
  w.u32(0);  // cosine flag: the stored values do not carry the light's cosine
  w.u32(xml.size());
  w.text(xml);
  w.u32(names.size());
  for (auto n : names) {
    w.u32(n.size());
    w.text(n);
  }
  w.u32(g.view_angles.size());
  for (const Vec2d& v : g.view_angles) {
    w.f32(v.x);
    w.f32(v.y);
    w.u32(g.light_angles.size());
    for (const Vec2d& l : g.light_angles) {
      w.f32(l.x);
      w.f32(l.y);
    }
  }
  w.u32(btf.resolution());
  w.u32(btf.resolution());
}

float stored_value(const Btf& btf, const GridSampling& g, int texel, int view, int light, int c) {
  const float b = btf.data()[btf.offset(texel, view, light) + c];
  const double f = g.light_factor[light];
  return f == 1.0 ? b : static_cast<float>(b / f);
}

void check_write_options(const UboWriteOptions& o) {
  if (o.scalar_bytes != 2 && o.scalar_bytes != 4)
    throw ParameterError(fmt::format("FMF scalar size {} must be 2 or 4 bytes", o.scalar_bytes));
  if (o.components < 0) throw ParameterError("FMF component count must be >= 0");
  if (o.scan_lines_per_chunk < 1) throw ParameterError("BDI scan lines per chunk must be >= 1");
}

}  // namespace

std::string ubo_btf_format(const fs::path& file) {
  ByteReader r(file);
  const std::string sig = read_signature(r);
  for (const Signature& s : kSignatures)
    if (s.text == sig) return std::string(s.format);
  return {};
}

MeasuredBtf read_ubo_btf(const fs::path& file, const MeasuredImportOptions& options) {
  ByteReader r(file);
  Header h = read_common(r);
  if (h.width != h.height)
    throw InputError(file, fmt::format("the texture is {} x {}; prtlab's BTF tile must be square "
                                       "(crop it first)",
                                       h.width, h.height));
  // The options and the size of the import, before the decoder allocates anything per texel.
  check_measured_import(file, static_cast<int>(h.width), options);
  const std::string format = h.format;
  Decoded d = format == "FMF"    ? decode_fmf(r, std::move(h))
              : format == "DFMF" ? decode_dfmf(r, std::move(h))
                                 : decode_bdi(r, std::move(h));
  MeasuredSource source;
  source.file = file;
  source.resolution = static_cast<int>(d.header.width);
  source.views = d.header.views;
  source.lights = d.header.lights;
  source.cosine_in_data = d.header.cosine_flag;
  source.tile = std::move(d.tile);
  source.material = "ubo:" + file.stem().string();
  source.parameters = {{"source_format", "ubo-" + lower_copy(format)},
                       {"source", file.string()},
                       {"signature", d.header.signature},
                       {"cosine_flag", d.header.cosine_flag},
                       {"rgb_scale_factor", d.header.rgb_scale},
                       {"format_parameters", d.parameters}};
  return resample_measured(source, options);
}

void write_ubo_fmf(const Btf& btf, const fs::path& file, const UboWriteOptions& options) {
  check_write_options(options);
  const GridSampling g = grid_sampling(btf, options.cosine);
  const std::size_t rows = static_cast<std::size_t>(3) * btf.light_count() * btf.view_count();
  const std::size_t cols = static_cast<std::size_t>(btf.texel_count());
  const std::size_t full = std::min(rows, cols);
  if (static_cast<std::size_t>(options.components) > full)
    throw ParameterError(
        fmt::format("{} FMF components requested; the {} x {} matrix has rank "
                    "at most {}",
                    options.components, rows, cols, full));
  // B[r][s], r = c + 3 (l + M v), s = texel.
  auto value = [&](std::size_t r, std::size_t s) {
    const int c = static_cast<int>(r % 3);
    const std::size_t lv = r / 3;
    const int l = static_cast<int>(lv % btf.light_count());
    const int v = static_cast<int>(lv / btf.light_count());
    return stored_value(btf, g, static_cast<int>(s), v, l, c);
  };
  ByteWriter w;
  write_common(w, "!FMF12FCER", btf, g);
  w.u32(0);  // rotations
  w.u8(2);   // header version
  w.u32(0);  // no dynamic range reduction
  w.u32(0);  // no height map
  w.u32(0);
  const int bytes = options.scalar_bytes;
  if (options.components == 0) {
    // One factor the identity: the product reproduces every value exactly (one non-zero term).
    const std::size_t p = full;
    w.u32(p);
    w.u8(static_cast<std::uint8_t>(bytes));
    w.u32(p);
    w.u32(rows);
    w.u32(cols);
    for (std::size_t k = 0; k < p; ++k) w.scalar(1.0f, bytes);
    const bool identity_v = cols <= rows;
    for (std::size_t r = 0; r < rows; ++r)
      for (std::size_t k = 0; k < p; ++k)
        w.scalar(identity_v ? value(r, k) : (r == k ? 1.0f : 0.0f), bytes);
    for (std::size_t s = 0; s < cols; ++s)
      for (std::size_t k = 0; k < p; ++k)
        w.scalar(identity_v ? (s == k ? 1.0f : 0.0f) : value(k, s), bytes);
  } else {
    Eigen::MatrixXd b(rows, cols);
    for (std::size_t r = 0; r < rows; ++r)
      for (std::size_t s = 0; s < cols; ++s)
        b(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(s)) = value(r, s);
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(b, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::Index p = options.components;
    w.u32(p);
    w.u8(static_cast<std::uint8_t>(bytes));
    w.u32(p);
    w.u32(rows);
    w.u32(cols);
    for (Eigen::Index k = 0; k < p; ++k)
      w.scalar(static_cast<float>(svd.singularValues()(k)), bytes);
    for (Eigen::Index r = 0; r < static_cast<Eigen::Index>(rows); ++r)
      for (Eigen::Index k = 0; k < p; ++k) w.scalar(static_cast<float>(svd.matrixU()(r, k)), bytes);
    for (Eigen::Index s = 0; s < static_cast<Eigen::Index>(cols); ++s)
      for (Eigen::Index k = 0; k < p; ++k)
        w.scalar(static_cast<float>(svd.matrixV()(s, k) * svd.singularValues()(k)), bytes);
  }
  write_bytes_atomically(file, w.bytes());
}

void write_ubo_bdi(const Btf& btf, const fs::path& file, const UboWriteOptions& options) {
  check_write_options(options);
  const GridSampling g = grid_sampling(btf, options.cosine);
  const int u = btf.resolution();
  const int lines = std::min(options.scan_lines_per_chunk, u);
  ByteWriter w;
  write_common(w, "!BDIF06R2!", btf, g);
  w.u32(lines);
  w.u8(2);  // sparse uncompressed
  for (int t = 0; t < btf.texel_count(); ++t) w.u8(1);
  w.u32(0);  // rotations
  const int per_chunk = u * lines;
  const std::size_t abrdf = static_cast<std::size_t>(3) * btf.light_count() * btf.view_count();
  for (int first = 0; first < btf.texel_count(); first += per_chunk) {
    const int n = std::min(per_chunk, btf.texel_count() - first);
    w.u32(static_cast<std::uint64_t>(n) * abrdf * 2);
    for (int t = first; t < first + n; ++t)
      for (int v = 0; v < btf.view_count(); ++v)
        for (int l = 0; l < btf.light_count(); ++l)
          for (int c = 0; c < 3; ++c) w.put(float_to_half(stored_value(btf, g, t, v, l, c)));
  }
  write_bytes_atomically(file, w.bytes());
}

}  // namespace prt
