// Times OpenImageIO's TextureSystem::texture() per filter on one thread, in C++, for
// `conetrace bench textures`: the rate a C++ renderer calling OpenImageIO gets, with no
// interpreter in between.
//
// usage: oiio_texture_bench TEXTURE.tx QUERIES.csv FILTERS MAX_ANISO CACHE_MB SECONDS [wall]
//   QUERIES   a header line, then s,t,dsdx,dtdx,dsdy,dtdy per line
//   FILTERS   comma-separated: closest, bilinear, trilinear, aniso
//   CACHE_MB  the ImageCache's max_memory_MB
//   SECONDS   minimum measuring time per filter: the thread's CPU time, or with "wall" the
//             wall clock
// Prints "cache_mb <MB>" (as OpenImageIO reports it back) and "<filter> <ns>" (nanoseconds
// per lookup: the fastest of three timed passes, each repeating the query set until SECONDS
// have passed).
//
// The calls are the fastest OpenImageIO offers a renderer: a TextureHandle resolved once and
// the thread's Perthread info passed to every call, as OSL and production renderers do.
// Options as in tests/oiio/oiio_lookup.py: InterpBilinear (InterpClosest for "closest"),
// MipModeNoMIP / NoMIP / Trilinear / Aniso, conservative_filter, periodic wrap, 4 channels.
#include <OpenImageIO/texture.h>

#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace OIIO;

namespace {

struct Query {
    float s, t, dsdx, dtdx, dsdy, dtdy;
};

clockid_t timing_clock = CLOCK_THREAD_CPUTIME_ID;

double seconds_now() {
    timespec now;
    clock_gettime(timing_clock, &now);
    return now.tv_sec + now.tv_nsec * 1e-9;
}

bool read_queries(const char* path, std::vector<Query>& queries) {
    std::ifstream in(path);
    std::string line;
    if (!std::getline(in, line))
        return false;
    while (std::getline(in, line)) {
        Query q;
        if (std::sscanf(line.c_str(), "%f,%f,%f,%f,%f,%f", &q.s, &q.t, &q.dsdx, &q.dtdx,
                        &q.dsdy, &q.dtdy) == 6)
            queries.push_back(q);
    }
    return !queries.empty();
}

bool options_for(const std::string& filter, int max_aniso, TextureOpt& opt) {
    opt.interpmode = filter == "closest" ? TextureOpt::InterpClosest : TextureOpt::InterpBilinear;
    if (filter == "closest" || filter == "bilinear")
        opt.mipmode = TextureOpt::MipModeNoMIP;
    else if (filter == "trilinear")
        opt.mipmode = TextureOpt::MipModeTrilinear;
    else if (filter == "aniso")
        opt.mipmode = TextureOpt::MipModeAniso;
    else
        return false;
    opt.swrap = opt.twrap = TextureOpt::WrapPeriodic;
    opt.anisotropic = max_aniso;
    opt.conservative_filter = true;
    return true;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 7 && !(argc == 8 && std::string(argv[7]) == "wall")) {
        std::fprintf(stderr,
                     "usage: %s TEXTURE QUERIES.csv FILTERS MAX_ANISO CACHE_MB SECONDS [wall]\n",
                     argv[0]);
        return 2;
    }
    if (argc == 8)
        timing_clock = CLOCK_MONOTONIC;
    std::vector<Query> queries;
    if (!read_queries(argv[2], queries)) {
        std::fprintf(stderr, "%s: no queries\n", argv[2]);
        return 2;
    }
    const int max_aniso = std::atoi(argv[4]);
    const float cache_mb = std::strtof(argv[5], nullptr);
    const double seconds = std::strtod(argv[6], nullptr);

    TextureSystem* ts = TextureSystem::create(false);
    ts->attribute("max_memory_MB", cache_mb);
    float reported_mb = 0;
    ts->getattribute("max_memory_MB", TypeDesc::FLOAT, &reported_mb);
    std::printf("cache_mb %g\n", reported_mb);

    TextureSystem::Perthread* thread_info = ts->get_perthread_info();
    TextureSystem::TextureHandle* handle = ts->get_texture_handle(ustring(argv[1]));
    if (!handle || !ts->good(handle)) {
        std::fprintf(stderr, "%s: OpenImageIO cannot open it: %s\n", argv[1],
                     ts->geterror().c_str());
        return 1;
    }

    std::stringstream filters(argv[3]);
    std::string filter;
    while (std::getline(filters, filter, ',')) {
        TextureOpt opt;
        if (!options_for(filter, max_aniso, opt)) {
            std::fprintf(stderr, "unknown filter '%s'\n", filter.c_str());
            return 2;
        }
        float sum[4] = {0, 0, 0, 0};
        float result[4];
        // One untimed pass reads every tile the queries touch, as conetrace's side warms.
        for (const Query& q : queries) {
            if (!ts->texture(handle, thread_info, opt, q.s, q.t, q.dsdx, q.dtdx, q.dsdy, q.dtdy,
                             4, result)) {
                std::fprintf(stderr, "%s: lookup failed: %s\n", argv[1], ts->geterror().c_str());
                return 1;
            }
        }
        double best = 1e300;
        for (int pass = 0; pass < 3; ++pass) {
            const double start = seconds_now();
            double elapsed = 0;
            size_t lookups = 0;
            do {
                for (const Query& q : queries) {
                    ts->texture(handle, thread_info, opt, q.s, q.t, q.dsdx, q.dtdx, q.dsdy,
                                q.dtdy, 4, result);
                    for (int c = 0; c < 4; ++c)
                        sum[c] += result[c];
                }
                lookups += queries.size();
                elapsed = seconds_now() - start;
            } while (elapsed < seconds / 3);
            const double ns = elapsed / lookups * 1e9;
            best = ns < best ? ns : best;
        }
        // The sum is printed to stderr so the compiler keeps every lookup.
        std::fprintf(stderr, "%s checksum %g\n", filter.c_str(), sum[0] + sum[1] + sum[2] + sum[3]);
        std::printf("%s %.2f\n", filter.c_str(), best);
    }
    TextureSystem::destroy(ts);
    return 0;
}
