// glint/photons/selective_tracing.hpp: selective photon tracing for scenes that change from
// frame to frame (Larsen 2004, ch. 9; after Dmitriev et al. 2002).
//
// The photons of a set of N are split into G groups by their emission index: photon i belongs
// to group i mod G. With Halton emission (PhotonEmission::halton) photon i leaves from Halton
// point i + 1, and when G divides a product of powers of the bases 2, 3, 5, 7, 11 every group's
// points lie in one elementary box of the sequence: similar emitter choice, start point and
// direction. Each photon keeps the path it stored (its photons, in walk order). Every frame,
// update() re-traces one photon of every group, round robin through the group's members (the
// pilot); a pilot whose stored hits differ from its record (another triangle, another hit
// point, a hit more or less) marks its group, and every photon of a marked group is traced
// again: its old photons are removed and the new ones stored. A group whose pilot follows its
// old path emits nothing, so a change in a part of the scene no photon of a group reaches costs
// that group one pilot a frame. A photon's random numbers depend only on (seed, index), so once
// every group has been piloted after the last change (ceil(N / G) frames) the maintained set
// equals a full re-trace of the current scene, photon for photon.
//
// The scene may move between updates with its triangle count and order fixed (the records name
// triangles by index); the emitters are rebuilt each update, so a moving light's photons change
// too (all of them, as Larsen notes).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glint/core/error.hpp>
#include <glint/core/parallel.hpp>
#include <glint/photons/photon_tracing.hpp>

namespace glint {

/// Selective tracing's knobs: the photon set, the number of groups, the path-change tolerance.
struct SelectiveTracingSettings {
    PhotonSettings photons;      ///< Photons, seed, emission (halton recommended), threads.
    std::size_t groups = 2310;   ///< G: 2 * 3 * 5 * 7 * 11, one elementary box per group; in [1, photons].
    float tolerance = 1e-4f;     ///< Hit points farther apart than tolerance * max(1, |x|) differ; >= 0.

    /// Throws Error for 0 photons, groups outside [1, photons] or a negative tolerance.
    void validate() const {
        if (photons.photons == 0) throw Error("glint::SelectivePhotons: photons must be positive (got 0)");
        if (groups == 0 || groups > photons.photons)
            throw Error("glint::SelectivePhotons: groups must be in [1, photons] (got " + std::to_string(groups) + ")");
        if (!(tolerance >= 0.0f)) throw Error("glint::SelectivePhotons: tolerance must be non-negative");
    }
};

/// A photon added to or removed from the maintained set (for the texel caches' priorities).
struct PhotonChange {
    std::uint32_t triangle;  ///< Index of the scene triangle the photon lies on.
    float luminance;  ///< Luminance of its power.
    bool bounced;     ///< The photon was reflected diffusely at least once before it was stored.
};

/// What one update did.
struct SelectiveFrame {
    std::size_t pilots = 0;           ///< Photons re-traced to test their paths.
    std::size_t groups_changed = 0;   ///< Groups whose pilot's path changed.
    std::size_t reemitted = 0;        ///< Photons traced again (whole groups).
    /// Stored photons the update removed (old paths of re-traced photons).
    std::vector<PhotonChange> removed, added;  ///< Stored photons the update added (their new paths).
};

/// A photon set maintained across frames of a changing scene by selective photon tracing
/// (Larsen 2004, ch. 9): built by tracing every photon, then updated once per frame.
template <Scalar T>
class SelectivePhotons {
public:
    /// Traces every photon in `s` and keeps their paths.
    template <RayAccelerator A>
    SelectivePhotons(const Scene<T>& s, const A& accel, const SelectiveTracingSettings& settings) : settings_(settings) {
        settings_.validate();
        paths_.resize(settings_.photons.photons);
        cursor_.assign(settings_.groups, 0);
        const PhotonEmitters<T> emitters(s);
        std::vector<std::uint32_t> all(settings_.groups);
        for (std::size_t g = 0; g < all.size(); ++g) all[g] = std::uint32_t(g);
        retrace_groups(s, accel, emitters, all);
    }

    /// The settings the set was built with.
    const SelectiveTracingSettings& settings() const { return settings_; }
    /// Number of photons in group g (those with index i mod G = g), for g < groups.
    std::size_t group_size(std::size_t g) const { return (paths_.size() - g + settings_.groups - 1) / settings_.groups; }

    /// One frame: pilots every group, re-traces the groups whose pilot changed (see the header).
    template <RayAccelerator A>
    SelectiveFrame update(const Scene<T>& s, const A& accel) {
        const PhotonEmitters<T> emitters(s);
        const std::size_t G = settings_.groups;
        std::vector<char> changed(G, 0);
        detail::parallel_blocks(int((G + 63) / 64), settings_.photons.threads, [&](std::atomic<int>& next) {
            for (int b = next++; b < int((G + 63) / 64); b = next++)
                for (std::size_t g = std::size_t(b) * 64; g < std::min(G, std::size_t(b + 1) * 64); ++g) {
                    const std::size_t i = g + cursor_[g] * G;
                    PhotonSet fresh;
                    trace_photon(s, accel, emitters, settings_.photons, i, fresh);
                    changed[g] = !same_path(paths_[i], fresh);
                }
        });
        SelectiveFrame frame;
        frame.pilots = G;
        std::vector<std::uint32_t> marked;
        for (std::size_t g = 0; g < G; ++g) {
            if (changed[g]) marked.push_back(std::uint32_t(g));
            cursor_[g] = (cursor_[g] + 1) % group_size(g);
        }
        frame.groups_changed = marked.size();
        for (std::uint32_t g : marked) {
            frame.reemitted += group_size(g);
            for (std::size_t i = g; i < paths_.size(); i += G) changes(paths_[i], frame.removed);
        }
        retrace_groups(s, accel, emitters, marked);
        for (std::uint32_t g : marked)
            for (std::size_t i = g; i < paths_.size(); i += G) changes(paths_[i], frame.added);
        return frame;
    }

    /// The maintained photons, in the order trace_photons stores them (by photon index).
    PhotonSet photons() const {
        PhotonSet out;
        out.emitted = paths_.size();
        for (const PhotonSet& p : paths_) append_photons(out, p);
        return out;
    }

private:
    template <RayAccelerator A>
    void retrace_groups(const Scene<T>& s, const A& accel, const PhotonEmitters<T>& emitters,
                        const std::vector<std::uint32_t>& groups) {
        detail::parallel_blocks(int(groups.size()), settings_.photons.threads, [&](std::atomic<int>& next) {
            for (int k = next++; k < int(groups.size()); k = next++)
                for (std::size_t i = groups[std::size_t(k)]; i < paths_.size(); i += settings_.groups) {
                    paths_[i] = PhotonSet{};
                    trace_photon(s, accel, emitters, settings_.photons, i, paths_[i]);
                }
        });
    }

    bool same_point(const Vec3<float>& a, const Vec3<float>& b) const {
        const float m = std::max({1.0f, std::abs(a.x), std::abs(a.y), std::abs(a.z)});
        return glm::length(a - b) <= settings_.tolerance * m;
    }

    bool same_list(const std::vector<Photon>& a, const std::vector<std::uint32_t>& ta, const std::vector<Photon>& b,
                   const std::vector<std::uint32_t>& tb) const {
        if (a.size() != b.size() || ta != tb) return false;
        for (std::size_t k = 0; k < a.size(); ++k)
            if (!same_point(a[k].position, b[k].position)) return false;
        return true;
    }

    bool same_path(const PhotonSet& a, const PhotonSet& b) const {
        return same_list(a.global, a.global_triangle, b.global, b.global_triangle) &&
               same_list(a.caustic, a.caustic_triangle, b.caustic, b.caustic_triangle);
    }

    /// Appends one photon's stored hits as changes. Its first global photon is direct light
    /// when it stored no caustic photon and direct hits are stored.
    void changes(const PhotonSet& p, std::vector<PhotonChange>& out) const {
        for (std::size_t k = 0; k < p.caustic.size(); ++k)
            out.push_back({p.caustic_triangle[k], p.caustic[k].power().luminance(), false});
        const bool direct_first = p.caustic.empty() && settings_.photons.store_direct;
        for (std::size_t k = 0; k < p.global.size(); ++k)
            out.push_back({p.global_triangle[k], p.global[k].power().luminance(), !(direct_first && k == 0)});
    }

    SelectiveTracingSettings settings_;
    std::vector<PhotonSet> paths_;       // per photon index: what it stored, in walk order
    std::vector<std::size_t> cursor_;    // per group: the member piloted next
};

}  // namespace glint
