// libFuzzer target: Delaunay<double> on fuzzed points (the input read as doubles, 3 per
// point, at most 256 points). A glint::Error (non-finite or out-of-range coordinates) is a
// correct answer; otherwise every tetrahedron must be positively oriented and (for up to 64
// points) have no point strictly inside its circumsphere (000 section 5.2: the Bowyer-Watson
// mesh), checked with the exact predicates.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include <glint/occluders/delaunay.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<double> c(std::min<std::size_t>(size / sizeof(double), 3 * 256));
    if (!c.empty()) std::memcpy(c.data(), data, c.size() * sizeof(double));
    std::vector<glint::Vec3d> pts;
    for (std::size_t i = 0; i + 3 <= c.size(); i += 3) pts.emplace_back(c[i], c[i + 1], c[i + 2]);
    try {
        const glint::Delaunay<double> d(pts);
        const auto tets = d.all_tetrahedra();
        const auto& p = d.points();
        for (const auto& t : tets) {
            const auto& v = t.v;
            const glint::Vec3d& a = p[std::size_t(v[0])];
            const glint::Vec3d& b = p[std::size_t(v[1])];
            const glint::Vec3d& cc = p[std::size_t(v[2])];
            const glint::Vec3d& dd = p[std::size_t(v[3])];
            if (glint::orient3d(a, b, cc, dd) <= 0) __builtin_trap();
            if (p.size() > 68) continue;  // the brute-force empty-sphere check on small sets only
            for (const glint::Vec3d& e : p)
                if (e != a && e != b && e != cc && e != dd && glint::insphere(a, b, cc, dd, e) > 0) __builtin_trap();
        }
    } catch (const glint::Error&) {
    }
    return 0;
}
