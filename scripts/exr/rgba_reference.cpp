// rgba_reference.cpp -- helper for scripts/exr/reference.py (not built or run by CI).
//
// Uses OpenEXR's own C++ library (libOpenEXR 3.x, e.g. Debian's libopenexr-dev) for what
// the OpenEXR Python bindings do not offer. reference.py compiles it on the fly:
//
//   g++ -std=c++17 -O2 rgba_reference.cpp -o rgba_reference $(pkg-config --cflags --libs OpenEXR)
//
// Commands (one per run; results on stdout as plain "key value..." lines, binary data in files):
//
//   rgba_reference version
//       "version <OPENEXR_VERSION_STRING>"
//
//   rgba_reference rgba FILE OUT.bin
//       Reads FILE with Imf::RgbaInputFile (first part, default layer: luminance/chroma
//       reconstruction, luminance weights from the file's chromaticities, missing channels
//       filled as RgbaInputFile fills them) over the whole data window and writes the
//       Imf::Rgba halves to OUT.bin, row-major (y outer, x inner), R G B A per pixel,
//       each half as its 16 bits little-endian.
//       Prints "rgba <xmin> <ymin> <xmax> <ymax> <RgbaChannels mask>".
//
//   rgba_reference header FILE
//       For every part and channel: "channel <part> <index> <half|float|uint> <xs> <ys> <name>".
//       For every part: "chroma <part> none" when the part has no chromaticities attribute,
//       otherwise "chroma <part> <differs 0|1> rx ry gx gy bx by wx wy m00 m01 ... m22"
//       where differs compares with Imf::Chromaticities() (Rec. 709, D65) using OpenEXR's
//       operator!=, and m is the column-vector matrix (rgb709 = M * rgb_file) taken from
//       Imf::RGBtoXYZ(file, 1) * Imf::XYZtoRGB(Chromaticities(), 1). Imath's matrices act on
//       row vectors (w = v * M), so the product is transposed before printing.
//
//   rgba_reference dump FILE OUTDIR
//       Independent read of every flat (non-deep) part at resolution level 0 with
//       Imf::InputPart / Imf::TiledInputPart (level 0,0), one file per channel:
//       OUTDIR/<part>_<channel index>.bin holding the samples over the data window, row-major,
//       only sampled positions (x % xs == 0, y % ys == 0, absolute coordinates), each in its
//       stored type, little-endian. Prints "dump <part> <index> <nx> <ny> <bytes/sample> <name>"
//       per channel and "deep <part>" for deep parts. Used to cross-check the Python bindings.
//
//   rgba_reference selftest
//       Checks the matrix convention with known vectors and prints "selftest ok" or fails.

#include <ImfChannelList.h>
#include <ImfChromaticities.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfPartType.h>
#include <ImfRgbaFile.h>
#include <ImfStandardAttributes.h>
#include <ImfTiledInputPart.h>
#include <OpenEXRConfig.h>
#include <ImathMatrix.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

using namespace Imf;
using namespace Imath;

namespace {

long long floor_div(long long a, long long b) {
    long long q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
    return q;
}

long long ceil_div(long long a, long long b) { return -floor_div(-a, b); }

void write_file(const std::string& path, const void* data, size_t n) {
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error("cannot open " + path);
    if (n && std::fwrite(data, 1, n, f) != n) {
        std::fclose(f);
        throw std::runtime_error("short write " + path);
    }
    std::fclose(f);
}

// Column-vector matrix M (row-major, M[r][c]) with rgb709 = M * rgb_file.
void to_rec709(const Chromaticities& file, double out[3][3]) {
    M44f a = RGBtoXYZ(file, 1.0f);
    M44f b = XYZtoRGB(Chromaticities(), 1.0f);
    M44f rowvec = a * b;  // v709 = v_file * rowvec  (row vectors)
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) out[r][c] = rowvec[c][r];  // transpose
}

int cmd_rgba(const char* path, const char* out) {
    RgbaInputFile in(path);
    Box2i dw = in.dataWindow();
    long long w = (long long)dw.max.x - dw.min.x + 1;
    long long h = (long long)dw.max.y - dw.min.y + 1;
    std::vector<Rgba> px((size_t)(w * h));
    // Base pointer so that pixel (x, y) lands at px[(y - ymin) * w + (x - xmin)].
    Rgba* base = px.data() - (ptrdiff_t)dw.min.x - (ptrdiff_t)dw.min.y * (ptrdiff_t)w;
    in.setFrameBuffer(base, 1, (size_t)w);
    in.readPixels(dw.min.y, dw.max.y);
    static_assert(sizeof(Rgba) == 8, "Rgba is 4 halves");
    write_file(out, px.data(), px.size() * sizeof(Rgba));
    std::printf("rgba %d %d %d %d %d\n", dw.min.x, dw.min.y, dw.max.x, dw.max.y, (int)in.channels());
    return 0;
}

const char* type_name(PixelType t) {
    switch (t) {
        case HALF: return "half";
        case FLOAT: return "float";
        case UINT: return "uint";
        default: return "unknown";
    }
}

int cmd_header(const char* path) {
    MultiPartInputFile file(path);
    for (int p = 0; p < file.parts(); ++p) {
        const Header& hdr = file.header(p);
        int i = 0;
        for (ChannelList::ConstIterator it = hdr.channels().begin(); it != hdr.channels().end(); ++it, ++i)
            std::printf("channel %d %d %s %d %d %s\n", p, i, type_name(it.channel().type),
                        it.channel().xSampling, it.channel().ySampling, it.name());
        if (!hasChromaticities(hdr)) {
            std::printf("chroma %d none\n", p);
            continue;
        }
        const Chromaticities& c = chromaticities(hdr);
        double m[3][3];
        to_rec709(c, m);
        std::printf("chroma %d %d %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g", p,
                    (c != Chromaticities()) ? 1 : 0, c.red.x, c.red.y, c.green.x, c.green.y,
                    c.blue.x, c.blue.y, c.white.x, c.white.y);
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k) std::printf(" %.9g", m[r][k]);
        std::printf("\n");
    }
    return 0;
}

size_t pixel_size(PixelType t) {
    switch (t) {
        case HALF: return 2;
        case FLOAT: return 4;
        case UINT: return 4;
        default: throw std::runtime_error("unknown pixel type");
    }
}

int cmd_dump(const char* path, const std::string& outdir) {
    MultiPartInputFile file(path);
    for (int p = 0; p < file.parts(); ++p) {
        const Header& hdr = file.header(p);
        std::string type = hdr.hasType() ? hdr.type() : std::string(hdr.hasTileDescription() ? TILEDIMAGE : SCANLINEIMAGE);
        if (type == DEEPSCANLINE || type == DEEPTILE) {
            std::printf("deep %d\n", p);
            continue;
        }
        const Box2i& dw = hdr.dataWindow();
        FrameBuffer fb;
        std::vector<std::vector<char>> bufs;
        struct Info { std::string name; long long nx, ny; size_t sz; };
        std::vector<Info> infos;
        for (ChannelList::ConstIterator it = hdr.channels().begin(); it != hdr.channels().end(); ++it) {
            const Channel& ch = it.channel();
            long long xs = ch.xSampling, ys = ch.ySampling;
            long long x0 = ceil_div(dw.min.x, xs), x1 = floor_div(dw.max.x, xs);  // in sample units
            long long y0 = ceil_div(dw.min.y, ys), y1 = floor_div(dw.max.y, ys);
            long long nx = x1 >= x0 ? x1 - x0 + 1 : 0, ny = y1 >= y0 ? y1 - y0 + 1 : 0;
            size_t sz = pixel_size(ch.type);
            bufs.emplace_back((size_t)(nx * ny) * sz + 1);
            char* buf = bufs.back().data();
            size_t xstride = sz, ystride = sz * (size_t)nx;
            // OpenEXR addresses sample (x, y) at base + (x/xs)*xStride + (y/ys)*yStride.
            char* base = buf - (ptrdiff_t)x0 * (ptrdiff_t)xstride - (ptrdiff_t)y0 * (ptrdiff_t)ystride;
            fb.insert(it.name(), Slice(ch.type, base, xstride, ystride, ch.xSampling, ch.ySampling));
            infos.push_back({it.name(), nx, ny, sz});
        }
        if (type == TILEDIMAGE) {
            TiledInputPart part(file, p);
            part.setFrameBuffer(fb);
            part.readTiles(0, part.numXTiles(0) - 1, 0, part.numYTiles(0) - 1, 0, 0);
        } else {
            InputPart part(file, p);
            part.setFrameBuffer(fb);
            part.readPixels(dw.min.y, dw.max.y);
        }
        for (size_t i = 0; i < infos.size(); ++i) {
            const Info& in = infos[i];
            write_file(outdir + "/" + std::to_string(p) + "_" + std::to_string(i) + ".bin", bufs[i].data(),
                       (size_t)(in.nx * in.ny) * in.sz);
            std::printf("dump %d %zu %lld %lld %zu %s\n", p, i, in.nx, in.ny, in.sz, in.name.c_str());
        }
    }
    return 0;
}

int cmd_selftest() {
    double m[3][3];
    // Identity for Rec. 709 itself.
    to_rec709(Chromaticities(), m);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            if (std::fabs(m[r][c] - (r == c ? 1.0 : 0.0)) > 1e-5) {
                std::printf("selftest fail identity\n");
                return 1;
            }
    // XYZ primaries (R=X, G=Y, B=Z, white E): D65 white XYZ (0.95047, 1, 1.08883) scaled to
    // white E's normalisation must give ~ (1, 1, 1) in Rec. 709; pure Y row must match the
    // standard XYZ->sRGB green column (-1.5372, 1.8758, -0.2040) up to rounding.
    Chromaticities xyz(V2f(1, 0), V2f(0, 1), V2f(0, 0), V2f(1.0f / 3, 1.0f / 3));
    to_rec709(xyz, m);
    double v[3] = {0.95047, 1.0, 1.08883}, o[3];
    for (int r = 0; r < 3; ++r) o[r] = m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2];
    for (int r = 0; r < 3; ++r)
        if (std::fabs(o[r] - 1.0) > 2e-3) {
            std::printf("selftest fail white %g %g %g\n", o[0], o[1], o[2]);
            return 1;
        }
    double g[3] = {-1.5372, 1.8758, -0.2040};
    for (int r = 0; r < 3; ++r)
        if (std::fabs(m[r][1] - g[r]) > 2e-3) {
            std::printf("selftest fail green column %g %g %g\n", m[0][1], m[1][1], m[2][1]);
            return 1;
        }
    std::printf("selftest ok\n");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::string cmd = argc > 1 ? argv[1] : "";
        if (cmd == "version") {
            std::printf("version %s\n", OPENEXR_VERSION_STRING);
            return 0;
        }
        if (cmd == "rgba" && argc == 4) return cmd_rgba(argv[2], argv[3]);
        if (cmd == "header" && argc == 3) return cmd_header(argv[2]);
        if (cmd == "dump" && argc == 4) return cmd_dump(argv[2], argv[3]);
        if (cmd == "selftest") return cmd_selftest();
        std::fprintf(stderr, "usage: %s version|selftest|rgba FILE OUT|header FILE|dump FILE DIR\n", argv[0]);
        return 2;
    } catch (const std::exception& e) {
        std::printf("error %s\n", e.what());
        std::fflush(stdout);
        return 3;
    }
}
