#pragma once
// Bonn University's binary BTF files (the BTFDBB / UBO2014 database; docs/btf.md "Measured
// BTFs"). The layout follows the reference reader and writer the database's authors published,
// btflib (github.com/cgbonn/btflib, matlab/@btf/private/: read_meta_data.m,
// read_bidir_sampling.m, read_common_header.m, read_ubo_fmf.m, read_ubo_dfmf.m, read_ubo_bdi.m,
// undecorrelate.m, restore_dynamic_range.m, decode_*_abrdf.m and the write_*.m counterparts),
// cross-checked against the Python reader of the same author (pysmtb, read_ubo_btf). All
// numbers little-endian; "half" is IEEE binary16.
//
//   signature     "!DFMF08FCR" | "!FMF12FCER" | "!FMF06FCR" | "!FMF06FC" | "!BDIF06R2!"
//   meta data     u32 size (bytes of this block, itself included), u32 version,
//                 char[80] measurement setup, char[80] image sensor, char[80] light source,
//                 f32 pixels per mm, f32[3] RGB scale factor,
//                 version > 1: u32 cosine flag (the light's cos(theta) is in the data),
//                 version > 2: u32 n, char[n] XML,
//                 version > 3: u32 channels C, C x (u32 n, char[n] name)   (else C = 3)
//   sampling      u32 views nV, nV x (f32 theta, f32 phi, u32 nL, nL x (f32 theta, f32 phi)),
//                 radians, theta from the normal, (sin t cos p, sin t sin p, cos t); every view
//                 must list the same nL lights (as btflib requires)
//   extent        u32 width, u32 height
//   FMF, DFMF:    signature ends in 'R': u32 rotations, rotations x f32[9]
//   FMF           "!FMF12FCER" only: u8 header version h; h >= 1: u32 dynamic range
//                 reduction (non-zero: values are log(x + 1e-5)); h >= 2: u32 rows, u32 cols,
//                 rows x cols half height map; h >= 3 unsupported.
//                 Then u32 components, u8 scalar size (2 half, 4 f32, 8 f64), u32 components P,
//                 u32 rows, u32 cols, P scalars S, rows x P U, cols x P SxV (row-major);
//                 value = sum_k U[r][k] SxV[s][k]. Either r = c + C (l + nL v) and s = texel
//                 (U holds ABRDFs), or r = c + C texel and s = l + nL v (U holds images); the
//                 first is taken when both fit, as btflib does.
//   DFMF          u32 components, i32 colour model, f32[3] colour mean, f32[3][3] colour matrix,
//                 then per channel: u8 scalar size, u32 P, u32 rows, u32 cols, S, U, SxV as in
//                 FMF with r = l + nL v, s = texel (or swapped); the channels are then turned
//                 back into RGB by the colour model (undecorrelate.m): 0 RGB, 1 YUV, 3 PCA
//                 (rgb = x M + mean), 4 YCoCg, 9 log Y + UV, 10 log Y, U, V, 11 log Y, U / Y,
//                 V / Y, 12 log RGB (eps 1e-5). Models 2 (Lab) and 5, 6 (spectral) are refused.
//   BDI           "!BDIF06R2!": u32 scan lines per chunk S, u8 compression (only 2, sparse
//                 uncompressed, is read), width x height u8 mask (x fastest; non-zero: the
//                 texel is stored), u32 rotations, rotations x f32[9], then chunks of
//                 width * S stored texels (the last one shorter): u32 bytes, then per texel
//                 nV x nL x C halves, c fastest, then l, then v.
//   texel         index x + width * y (btflib's decode_*_abrdf, pysmtb's reshape(height,
//                 width)) = prtlab's texel (x, y).
// After decoding: the dynamic range reduction is undone, then the cosine is divided out where
// the flag says the data has it (btflib's decode_abrdf), leaving an apparent BRDF; the
// import's LightCosine kCellMean multiplies it by c_j, kAsStored keeps the file's values. The
// RGB scale factor is recorded in the parameters, not applied (btflib does not apply it).
//
// Sizes from the header are checked against the file size before anything is allocated; a
// short, inconsistent or unsupported file is an InputError naming it.
#include <filesystem>
#include <string>

#include "prtlab/btf/btf.h"
#include "prtlab/btf/measured_btf.h"

namespace prt {

/// The format of a UBO file from its signature: "DFMF", "FMF" or "BDI" (InputError otherwise).
std::string ubo_btf_format(const std::filesystem::path& file);

/// Reads a DFMF, FMF or BDI file and resamples it (measured_btf.h). The texel tile must be
/// square. The default material name is "ubo:<file stem>".
MeasuredBtf read_ubo_btf(const std::filesystem::path& file,
                         const MeasuredImportOptions& options = {});

struct UboWriteOptions {
  /// FMF: 0 writes an exact factorisation (one factor the identity, the other the data); P > 0
  /// a rank-P truncated SVD (P at most min(rows, cols)).
  int components = 0;
  int scalar_bytes = 4;  ///< FMF scalars: 4 (f32) or 2 (half); BDI is always half
  /// kCellMean writes b / c_j (an apparent BRDF, cosine flag 0), kAsStored writes b.
  LightCosine cosine = LightCosine::kCellMean;
  int scan_lines_per_chunk = 4;  ///< BDI
};

/// Writes "!FMF12FCER" (header version 2, no height map, no rotations, U holding ABRDFs) at the
/// grid's cell-centre directions. Written to a temporary file, then renamed.
void write_ubo_fmf(const Btf& btf, const std::filesystem::path& file,
                   const UboWriteOptions& options = {});
/// Writes "!BDIF06R2!" (sparse uncompressed, every texel present).
void write_ubo_bdi(const Btf& btf, const std::filesystem::path& file,
                   const UboWriteOptions& options = {});

}  // namespace prt
