#include "hand_stream_format.h"

#include <algorithm>
#include <array>

namespace cvephands {
namespace wire {
namespace {

// Little-endian field writer / reader over a fixed buffer.
struct Writer {
  uint8_t* p;
  void u8(uint8_t v) { *p++ = v; }
  void u16(uint16_t v) { u8(uint8_t(v)), u8(uint8_t(v >> 8)); }
  void u32(uint32_t v) { putU32(p, v), p += 4; }
  void f64(double v) {
    uint64_t b;
    std::memcpy(&b, &v, 8);
    for (int i = 0; i < 8; ++i) u8(uint8_t(b >> (8 * i)));
  }
};
struct Reader {
  const uint8_t* p;
  uint8_t u8() { return *p++; }
  uint16_t u16() {
    const uint16_t v = uint16_t(p[0] | p[1] << 8);
    p += 2;
    return v;
  }
  uint32_t u32() {
    const uint32_t v = getU32(p);
    p += 4;
    return v;
  }
  double f64() {
    uint64_t b = 0;
    for (int i = 0; i < 8; ++i) b |= uint64_t(p[i]) << (8 * i);
    p += 8;
    double v;
    std::memcpy(&v, &b, 8);
    return v;
  }
};

std::array<uint32_t, 256> makeCrcTable() {
  std::array<uint32_t, 256> t{};
  for (uint32_t n = 0; n < 256; ++n) {
    uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[n] = c;
  }
  return t;
}

}  // namespace

void writeHeader(const Header& h, uint8_t* out) {
  Writer w{out};
  for (uint8_t m : kMagic) w.u8(m);
  w.u8(h.version), w.u8(h.method), w.u8(h.flags), w.u8(h.bits);
  w.u32(h.target_id), w.u32(h.sequence), w.u32(h.stamp_sec), w.u32(h.stamp_nsec);
  for (double o : h.origin) w.f64(o);
  w.f64(h.voxel_size);
  for (uint16_t d : h.dims) w.u16(d);
  w.u8(h.iso_byte), w.u8(h.reserved0);
  w.u32(h.reference_sequence);
  for (int16_t s : h.shift) w.u16(uint16_t(s));
  w.u16(h.reserved1);
  w.u32(h.band_count), w.u32(h.mask_bytes), w.u32(h.raw_size), w.u32(h.payload_size);
}

void readHeader(const uint8_t* in, Header* h) {
  Reader r{in + 4};
  h->version = r.u8(), h->method = r.u8(), h->flags = r.u8(), h->bits = r.u8();
  h->target_id = r.u32(), h->sequence = r.u32(), h->stamp_sec = r.u32(), h->stamp_nsec = r.u32();
  for (double& o : h->origin) o = r.f64();
  h->voxel_size = r.f64();
  for (uint16_t& d : h->dims) d = r.u16();
  h->iso_byte = r.u8(), h->reserved0 = r.u8();
  h->reference_sequence = r.u32();
  for (int16_t& s : h->shift) s = int16_t(r.u16());
  h->reserved1 = r.u16();
  h->band_count = r.u32(), h->mask_bytes = r.u32(), h->raw_size = r.u32(),
  h->payload_size = r.u32();
}

uint32_t crc32(const uint8_t* data, size_t size) {
  static const std::array<uint32_t, 256> table = makeCrcTable();
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xff] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

void aboveIso(const uint8_t* __restrict in, size_t n, uint8_t iso, uint8_t* __restrict out) {
  for (size_t i = 0; i < n; ++i) out[i] = in[i] > iso;
}
void xorInto(uint8_t* __restrict dst, const uint8_t* __restrict src, size_t n) {
  for (size_t i = 0; i < n; ++i) dst[i] ^= src[i];
}
void maskToBytes(const uint8_t* __restrict mask, size_t n, uint8_t* __restrict out) {
  for (size_t i = 0; i < n; ++i) out[i] = uint8_t(0 - mask[i]);
}

size_t classifyBand(const uint8_t* above, int nx, int ny, int nz, std::vector<uint8_t>* padded,
                    uint8_t* context) {
  // A one-sample ring of zeros around the volume makes every neighbour readable and is exactly
  // the "outside is below" rule.
  const size_t px = size_t(nx) + 2, pxy = px * (size_t(ny) + 2);
  padded->assign(pxy * (size_t(nz) + 2), 0);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      std::memcpy(padded->data() + (z + 1) * pxy + (y + 1) * px + 1,
                  above + size_t(nx) * (y + size_t(ny) * z), size_t(nx));
  size_t band = 0;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y) {
      const uint8_t* c = padded->data() + (z + 1) * pxy + (y + 1) * px + 1;
      uint8_t* out = context + size_t(nx) * (y + size_t(ny) * z);
      size_t row_band = 0;
      for (int x = 0; x < nx; ++x) {  // branch-free: GCC vectorises it
        const uint8_t u = c[x];
        const uint8_t k = uint8_t((u ^ c[x - 1]) + (u ^ c[x + 1]) + (u ^ c[x - px]) +
                                  (u ^ c[x + px]) + (u ^ c[x - pxy]) + (u ^ c[x + pxy]));
        out[x] = k ? uint8_t(u * 6 + k) : 0;
        row_band += k != 0;
      }
      band += row_band;
    }
  return band;
}

void shiftedMask(const uint8_t* mask, int nx, int ny, int nz, int sx, int sy, int sz,
                 uint8_t* out) {
  // Source x range [x0 + sx, x1 + sx) lies inside the volume; the rest of the row is 0.
  const int x0 = std::max(0, -sx), x1 = std::min(nx, nx - sx);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y) {
      uint8_t* row = out + size_t(nx) * (y + size_t(ny) * z);
      const int ry = y + sy, rz = z + sz;
      if (ry < 0 || ry >= ny || rz < 0 || rz >= nz || x0 >= x1) {
        std::memset(row, 0, size_t(nx));
        continue;
      }
      std::memset(row, 0, size_t(x0));
      std::memcpy(row + x0, mask + size_t(nx) * (ry + size_t(ny) * rz) + (x0 + sx),
                  size_t(x1 - x0));
      std::memset(row + x1, 0, size_t(nx - x1));
    }
}

}  // namespace wire
}  // namespace cvephands
