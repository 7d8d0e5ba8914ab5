// Runs the original WhyCode detector (CWhycon from the whycon-ros sources,
// built against them; see build.sh) on the detector bar's frames, as its
// ROS node would on a stream: one CWhycon, the node's default settings,
// `markers` markers to track. Prints one JSON line per frame, like
// apriltag.py: {"file", "ms", "markers": [{"id", "u", "v", "angle", "x",
// "y", "z", "n": [n0, n1, n2]}]}; "ms" is processImage alone. x, y, z
// are the original's (ROS body frame: x forward), n its normal in the
// optical frame, pointing away from the camera.
//
// whycon_bar DIR --diameter M --bits N --distance D --markers K
//            --fx F --fy F --cx C --cy C [--legacy]
// whycon_bar --serve: reads such argument lines (DIR first) from stdin and
//            answers each with its frames' lines and {"end": true}.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
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

struct Request {
    std::string dir;
    float diameter = 0.05f, fx = 1, fy = 1, cx = 0, cy = 0;
    int bits = 8, distance = 2, markers = 5;
    bool legacy = false;
};

static Request parse(const std::vector<std::string> &args)
{
    Request r;
    r.dir = args.empty() ? "." : args[0];
    for (size_t i = 1; i < args.size(); i++) {
        const std::string &a = args[i];
        auto next = [&]() { return i + 1 < args.size() ? args[++i].c_str() : "0"; };
        if (a == "--diameter") r.diameter = std::atof(next());
        else if (a == "--bits") r.bits = std::atoi(next());
        else if (a == "--distance") r.distance = std::atoi(next());
        else if (a == "--markers") r.markers = std::atoi(next());
        else if (a == "--fx") r.fx = std::atof(next());
        else if (a == "--fy") r.fy = std::atof(next());
        else if (a == "--cx") r.cx = std::atof(next());
        else if (a == "--cy") r.cy = std::atof(next());
        else if (a == "--legacy") r.legacy = true;
    }
    return r;
}

// One CWhycon per family, image size and marker count: building its ID table takes
// minutes at 16 bits, so a serving process keeps them.
static std::map<std::string, whycon::CWhycon *> detectors;

static int serve(const Request &r)
{
    std::vector<std::string> files;
    if (DIR *d = opendir(r.dir.c_str())) {
        while (dirent *e = readdir(d)) {
            std::string n = e->d_name;
            if (n.size() > 4 && n.substr(n.size() - 4) == ".pgm") files.push_back(n);
        }
        closedir(d);
    }
    std::sort(files.begin(), files.end());
    int w = 640, h = 480;
    std::vector<unsigned char> pixels;
    if (!files.empty() && !read_pgm(r.dir + "/" + files[0], w, h, pixels)) {
        std::fprintf(stderr, "%s: not an 8-bit binary PGM\n", files[0].c_str());
        return 1;
    }
    // Fewer markers than before crash updateConfiguration (it deletes past
    // the end): one per count too. All its detectors share one static pixel
    // buffer of the first image's size: serve one image size per process.
    std::string key = std::to_string(r.bits) + "/" + std::to_string(r.distance) + (r.legacy ? "L" : "") +
                      " " + std::to_string(w) + "x" + std::to_string(h) + " " + std::to_string(r.markers);
    whycon::CWhycon *&whycon = detectors[key];
    if (!whycon) {
        whycon = new whycon::CWhycon();
        // The ROS node's defaults (cfg/whycon.cfg): 360 ring samples.
        whycon->init(r.diameter, false, r.bits, 360, r.distance, r.markers, w, h);
    }
    // Node defaults: min size 30 px, tolerances 100 / 2 / 40 / 10 % / 5 px.
    whycon->updateConfiguration(!r.legacy, r.diameter, r.markers, 30, 1.0, 1.0, 100.0, 2.0, 40.0, 10.0, 5.0);
    std::vector<float> k = {r.fx, 0, r.cx, 0, r.fy, r.cy, 0, 0, 1};
    std::vector<float> dist = {0, 0, 0, 0, 0};
    whycon->updateCameraInfo(k, dist);
    whycon::CRawImage image(w, h, 1);

    for (const auto &name : files) {
        if (!read_pgm(r.dir + "/" + name, w, h, pixels)) {
            std::fprintf(stderr, "%s: not an 8-bit binary PGM\n", name.c_str());
            return 1;
        }
        image.updateImage(pixels.data(), w, h, 1);
        std::vector<whycon::SMarker> found;
        auto t0 = std::chrono::steady_clock::now();
        whycon->processImage(&image, found);
        double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        std::printf("{\"file\": \"%s\", \"ms\": %.4f, \"markers\": [", name.c_str(), ms);
        for (size_t j = 0; j < found.size(); j++) {
            const auto &m = found[j];
            std::printf("%s{\"id\": %d, \"u\": %.4f, \"v\": %.4f, \"angle\": %.6f, \"x\": %.6f, \"y\": %.6f, \"z\": %.6f, \"n\": [%.6f, %.6f, %.6f]}",
                        j ? ", " : "", m.seg.ID, m.obj.u, m.obj.v, m.obj.angle, m.obj.x, m.obj.y, m.obj.z,
                        m.obj.n0, m.obj.n1, m.obj.n2);
        }
        std::printf("]}\n");
    }
    std::fflush(stdout);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: whycon_bar DIR --diameter M --bits N --distance D --markers K --fx F --fy F --cx C --cy C [--legacy]\n"
                             "       whycon_bar --serve   (one such argument line per request on stdin)\n");
        return 2;
    }
    if (std::string(argv[1]) != "--serve") {
        return serve(parse(std::vector<std::string>(argv + 1, argv + argc)));
    }
    std::string line;
    while (std::getline(std::cin, line)) {
        std::istringstream words(line);
        std::vector<std::string> args{std::istream_iterator<std::string>(words), {}};
        if (serve(parse(args)) != 0) return 1;
        std::printf("{\"end\": true}\n");
        std::fflush(stdout);
    }
    return 0;
}
