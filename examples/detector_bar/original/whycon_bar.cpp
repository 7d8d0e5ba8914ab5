// Runs the original WhyCode detector (CWhycon from the whycon-ros sources,
// built against them; see build.sh) on the detector bar's frames, as its
// ROS node would on a stream: one CWhycon, the node's default settings,
// `markers` markers to track. Prints one JSON line per frame, like
// apriltag.py: {"file", "ms", "markers": [{"id", "u", "v", "angle", "x",
// "y", "z", "n": [n0, n1, n2]}]}; "ms" is processImage alone.
//
// whycon_bar DIR --diameter M --bits N --distance D --markers K
//            --fx F --fy F --cx C --cy C [--legacy]

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <fstream>
#include <iterator>
#include <algorithm>
#include <string>
#include <vector>

#include "whycon/CWhycon.h"

static bool read_pgm(const std::string &path, int &w, int &h, std::vector<unsigned char> &pixels)
{
    std::ifstream in(path, std::ios::binary);
    std::string magic;
    int maxval = 0;
    in >> magic >> w >> h >> maxval;
    if (!in || magic != "P5" || maxval > 255) return false;
    in.get();
    pixels.resize((size_t)w * h);
    in.read((char *)pixels.data(), pixels.size());
    return (bool)in;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: whycon_bar DIR --diameter M --bits N --distance D --markers K --fx F --fy F --cx C --cy C [--legacy]\n");
        return 2;
    }
    std::string dir = argv[1];
    float diameter = 0.05f, fx = 1, fy = 1, cx = 0, cy = 0;
    int bits = 8, distance = 2, markers = 5;
    bool legacy = false;
    for (int i = 2; i < argc; i++) {
        std::string a = argv[i];
        auto next = [&]() { return i + 1 < argc ? argv[++i] : (char *)"0"; };
        if (a == "--diameter") diameter = std::atof(next());
        else if (a == "--bits") bits = std::atoi(next());
        else if (a == "--distance") distance = std::atoi(next());
        else if (a == "--markers") markers = std::atoi(next());
        else if (a == "--fx") fx = std::atof(next());
        else if (a == "--fy") fy = std::atof(next());
        else if (a == "--cx") cx = std::atof(next());
        else if (a == "--cy") cy = std::atof(next());
        else if (a == "--legacy") legacy = true;
    }
    std::vector<std::string> files;
    if (DIR *d = opendir(dir.c_str())) {
        while (dirent *e = readdir(d)) {
            std::string n = e->d_name;
            if (n.size() > 4 && n.substr(n.size() - 4) == ".pgm") files.push_back(n);
        }
        closedir(d);
    }
    std::sort(files.begin(), files.end());

    whycon::CWhycon whycon;
    int w0 = 640, h0 = 480;
    std::vector<unsigned char> pixels;
    if (!files.empty() && read_pgm(dir + "/" + files[0], w0, h0, pixels)) {}
    // The ROS node's defaults (cfg/whycon.cfg): 360 ring samples, min size
    // 30 px, tolerances 100 / 2 / 40 / 10 % / 5 px.
    whycon.init(diameter, false, bits, 360, distance, markers, w0, h0);
    whycon.updateConfiguration(!legacy, diameter, markers, 30, 1.0, 1.0, 100.0, 2.0, 40.0, 10.0, 5.0);
    std::vector<float> k = {fx, 0, cx, 0, fy, cy, 0, 0, 1};
    std::vector<float> dist = {0, 0, 0, 0, 0};
    whycon.updateCameraInfo(k, dist);
    whycon::CRawImage image(w0, h0, 1);

    for (const auto &name : files) {
        int w, h;
        if (!read_pgm(dir + "/" + name, w, h, pixels)) {
            std::fprintf(stderr, "%s: not an 8-bit binary PGM\n", name.c_str());
            return 1;
        }
        image.updateImage(pixels.data(), w, h, 1);
        std::vector<whycon::SMarker> found;
        auto t0 = std::chrono::steady_clock::now();
        whycon.processImage(&image, found);
        double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        std::printf("{\"file\": \"%s\", \"ms\": %.4f, \"markers\": [", name.c_str(), ms);
        for (size_t j = 0; j < found.size(); j++) {
            const auto &m = found[j];
            std::printf("%s{\"id\": %d, \"u\": %.4f, \"v\": %.4f, \"angle\": %.6f, \"x\": %.6f, \"y\": %.6f, \"z\": %.6f, \"n\": [%.6f, %.6f, %.6f]}",
                        j ? ", " : "", m.seg.ID, m.obj.u, m.obj.v, m.obj.angle, m.obj.x, m.obj.y, m.obj.z,
                        m.obj.n0, m.obj.n1, m.obj.n2);
        }
        std::printf("]}\n");
        std::fflush(stdout);
    }
    return 0;
}
