// glint/photons/caustic_filter.hpp: the screen-space caustic filter (Larsen 2004, ch. 12), a
// CPU pass: caustic photons are splatted into the pixels they project to, where they pass a
// depth test against the surface the pixel sees, and the image of splatted power t is
// filtered with the 7 x 7 kernel
//   w(i, j) = sqrt(1 + 2 k^2 - (i^2 + j^2)),  |i|, |j| <= k = 3           (Larsen eq. 12.1)
// and divided by the world area of the pixel (Larsen eq. 12.2):
//   E(x, y) = sum_ij w(i, j) t(x + i, y + j) / (A(x, y) sum_ij w(i, j)),
// an irradiance (a kd / pi BRDF turns it into radiance). The weights are normalized, so a
// photon density that is uniform in the image gives its mean power per pixel over A.
//
// A(x, y), the world area the pixel covers at the surface it sees, is d^2 omega / cos: d the
// distance from the eye, omega the pixel's solid angle (du dv cos^3 of its angle off the axis,
// du dv its size on the image plane at distance 1), cos = n_s . n_e. Larsen's eq. 12.2 writes
// (n_s . n_e) 4 d^2 tan(f_x / 2 p_x) tan(f_y / 2 p_y), i.e. multiplies by the cosine and takes
// the centre pixel's solid angle; the footprint grows as 1 / cos at grazing views, which is
// what a uniform photon density on an oblique plane checks (tests/test_photons.cpp).
//
// Not physically correct, as Larsen says: the kernel spans a fixed 7 x 7 pixels, so the world
// radius of the estimate grows with distance and shrinks when zooming in; a caustic narrower
// than the kernel is blurred (its peak lowered, its edges widened), and photons are counted
// from neighbouring pixels on other surfaces (the kernel ignores depth; only the splat does
// not). Photons seen through mirrors or glass are not splatted. The depth test accepts a
// photon that lies within `depth_tolerance` times the pixel's depth of the tangent plane of
// the surface the pixel's centre sees, with its normal within 60 degrees of that surface's (a
// test on the view-axis distance alone rejects photons in the far half of an oblique pixel).
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/image.hpp>
#include <glint/core/math.hpp>
#include <glint/core/spectrum.hpp>
#include <glint/photons/photon.hpp>
#include <glint/tracer/scene.hpp>
#include <glint/trees/tree.hpp>

namespace glint {

/// The caustic filter's knobs (Larsen 2004, ch. 12): kernel size and the splat's depth test.
struct CausticFilterSettings {
    int k = 3;                     ///< Kernel half-width: (2k + 1)^2 pixels; in [0, 64].
    float depth_tolerance = 0.01f; ///< Distance off the pixel's tangent plane, relative to its depth; > 0.

    /// Throws Error for k outside [0, 64] or a depth_tolerance that is not positive.
    void validate() const {
        if (k < 0 || k > 64) throw Error("glint::caustic_filter: k must be in [0, 64] (got " + std::to_string(k) + ")");
        if (!(depth_tolerance > 0.0f)) throw Error("glint::caustic_filter: depth_tolerance must be positive");
    }
};

/// The kernel of eq. 12.1, (2k + 1)^2 weights, row by row.
inline std::vector<float> caustic_kernel(int k) {
    std::vector<float> w;
    for (int j = -k; j <= k; ++j)
        for (int i = -k; i <= k; ++i) w.push_back(std::sqrt(float(1 + 2 * k * k - (i * i + j * j))));
    return w;
}

/// What a pixel's centre sees: the screen buffers of the filter (Larsen's depth and n_s . n_e).
struct ScreenSurface {
    bool diffuse = false;    ///< A non-specular surface (caustics are splatted and shown there); false where the ray missed.
    float depth = 0.0f;      ///< Distance along the view axis (world units).
    float area = 0.0f;       ///< A: world area of the pixel's footprint.
    Vec3<float> normal{0.0f};  ///< Unit geometric normal, facing the eye.
    Vec3<float> position{0.0f};  ///< World-space point the pixel's centre sees.
};

/// The camera's projection: pixel of a point and the view-axis distance (the inverse of Camera::ray).
class ScreenProjection {
public:
    /// The projection of camera c onto a width x height image; throws Error for a size < 1.
    template <Scalar T>
    ScreenProjection(const Camera<T>& c, int width, int height)
        : eye_(c.eye), w_(safe_normalize(Vec3<float>(c.target - c.eye))), width_(width), height_(height) {
        if (width < 1 || height < 1) throw Error("glint::ScreenProjection: image size must be positive");
        u_ = safe_normalize(glm::cross(w_, Vec3<float>(c.up)), Vec3<float>(1, 0, 0));
        v_ = glm::cross(u_, w_);
        h_ = std::tan(float(c.fov_y) * 0.5f);
        aspect_ = float(width) / float(height);
    }
    /// Pixel index of p (or -1 outside the image), and p's distance along the view axis.
    long pixel(const Vec3<float>& p, float& depth) const {
        const Vec3<float> q = p - eye_;
        depth = glm::dot(q, w_);
        if (!(depth > 0.0f)) return -1;
        const float sx = (glm::dot(q, u_) / (depth * h_ * aspect_) + 1.0f) * 0.5f;
        const float sy = (1.0f - glm::dot(q, v_) / (depth * h_)) * 0.5f;
        if (!(sx >= 0.0f && sx < 1.0f && sy >= 0.0f && sy < 1.0f)) return -1;
        return long(sy * float(height_)) * width_ + long(sx * float(width_));
    }
    /// Solid angle of pixel (x, y): du dv cos^3 of its centre's angle off the view axis.
    float solid_angle(int x, int y) const {
        const float du = 2.0f * h_ * aspect_ / float(width_), dv = 2.0f * h_ / float(height_);
        const float a = (float(x) + 0.5f) * du - h_ * aspect_, b = h_ - (float(y) + 0.5f) * dv;
        return du * dv / std::pow(1.0f + a * a + b * b, 1.5f);
    }
    /// The unit view axis (from the eye toward the target).
    const Vec3<float>& axis() const { return w_; }

private:
    Vec3<float> eye_, w_, u_{}, v_{};
    int width_, height_;
    float h_ = 1.0f, aspect_ = 1.0f;
};

/// The screen buffers for scene s seen through its camera, one ray through each pixel centre.
template <RayAccelerator A, Scalar T = typename A::scalar_type>
std::vector<ScreenSurface> screen_surfaces(const Scene<T>& s, const A& accel, int width, int height) {
    const ScreenProjection proj(s.camera, width, height);
    std::vector<ScreenSurface> out(std::size_t(width) * std::size_t(height));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const Ray<T> ray = s.camera.ray((T(x) + T(0.5)) / T(width), (T(y) + T(0.5)) / T(height), T(width) / T(height));
            StoreHit<T> hit;
            if (!accel.closest_hit(ray, hit)) continue;
            const Vec3<T> ng = s.normal(hit.id);
            const Vec3<float> n(glm::dot(ng, ray.direction) < T(0) ? ng : -ng);
            const Vec3<float> p(ray.at(hit.t));
            ScreenSurface& o = out[std::size_t(y) * std::size_t(width) + std::size_t(x)];
            o.diffuse = !s.materials[s.material_of[hit.id]].specular();
            o.depth = glm::dot(p - Vec3<float>(s.camera.eye), proj.axis());
            const float cos_s = std::max(-glm::dot(n, Vec3<float>(ray.direction)), 1e-6f);
            o.area = float(hit.t * hit.t) * proj.solid_angle(x, y) / cos_s;
            o.normal = n;
            o.position = p;
        }
    return out;
}

/// Splat (depth-tested) and filter (eqs. 12.1, 12.2): per pixel irradiance from the caustic photons.
inline Image<Rgb<float>> caustic_filter(const ScreenProjection& proj, int width, int height,
                                        std::span<const ScreenSurface> screen, std::span<const Photon> photons,
                                        const CausticFilterSettings& settings = {}) {
    settings.validate();
    if (screen.size() != std::size_t(width) * std::size_t(height))
        throw Error("glint::caustic_filter: " + std::to_string(screen.size()) + " screen surfaces for a " +
                    std::to_string(width) + "x" + std::to_string(height) + " image");
    std::vector<Rgb<float>> t(screen.size(), Rgb<float>(0.0f));
    for (const Photon& p : photons) {
        float depth = 0.0f;
        const long i = proj.pixel(p.position, depth);
        if (i < 0) continue;
        const ScreenSurface& s = screen[std::size_t(i)];
        if (s.diffuse && std::abs(glm::dot(p.position - s.position, s.normal)) <= settings.depth_tolerance * s.depth &&
            glm::dot(p.normal(), s.normal) > 0.5f)
            t[std::size_t(i)] += p.power();
    }
    const int k = settings.k;
    const std::vector<float> w = caustic_kernel(k);
    float wsum = 0.0f;
    for (float v : w) wsum += v;
    Image<Rgb<float>> out(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const ScreenSurface& s = screen[std::size_t(y) * std::size_t(width) + std::size_t(x)];
            if (!s.diffuse || !(s.area > 0.0f)) continue;
            Rgb<float> sum(0.0f);
            for (int j = -k; j <= k; ++j)
                for (int i = -k; i <= k; ++i)
                    if (x + i >= 0 && x + i < width && y + j >= 0 && y + j < height)
                        sum += t[std::size_t(y + j) * std::size_t(width) + std::size_t(x + i)] * w[std::size_t((j + k) * (2 * k + 1) + i + k)];
            out.at(x, y) = sum / (s.area * wsum);
        }
    return out;
}

}  // namespace glint
