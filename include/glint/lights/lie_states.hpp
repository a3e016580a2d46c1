// glint/lights/lie_states.hpp: one local illumination environment (Fernandez 2004, §3.1):
// per light, its state in a cell and the blockers found for it, grown sample by sample by the
// state machine of §3.1.1 (Fig. 3.2), and frozen into the shading order with the masking of
// §3.2.
//
// The state machine, per light, for a shadow ray from a sampled surface point of the cell
// (Fig. 3.2):
//   absent     (the start: "occluded")  unblocked ray -> unoccluded; blocked ray -> absent;
//   unoccluded unblocked -> unoccluded; blocked by k -> partial, with the list {k};
//   partial    unblocked -> partial; blocked by k -> partial, k added to the list if new.
// As drawn, the figure forgets what blocked a light before a sample saw it, so a light can end
// unoccluded although a sampled point of the cell did not see it, against §3.1's definition
// (unoccluded iff every sampled point sees the light, absent iff none does, partial otherwise).
// LieRules::early_blockers (the default) keeps those blockers while the light is absent (§4.8's
// model does the same), and the first unblocked ray then makes it partial with them: the states
// are then exactly §3.1's, and lists hold only triangles that blocked a sampled ray. With
// early_blockers off the figure is followed as drawn. The three-state variant (§4.7) keeps no
// lists: its partial lights are tested against the whole scene. A sample where a light cannot
// contribute (behind the surface, outside its cone) casts no ray and changes nothing.
//
// Masking (§3.2, Weber's law): the cell keeps each light's largest contribution (luminance of
// f I cos / r^2, visibility included) and the smallest total over its samples; the dimmest
// lights are dropped, smallest largest-contribution first, while the sum of the dropped ones'
// largest contributions stays <= 2% of that minimum total. At every sampled point the dropped
// light is then <= 2% of the point's own total; at unsampled points it is not guaranteed.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glint/core/math.hpp>

namespace glint {

/// A light's state in a cell (§3.1): seen by no sampled point, by every one, or by some.
enum class LieState : std::uint8_t { absent, unoccluded, partial };

/// What one sample's shadow ray to one light found: a blocker triangle (>= 0), or one of these.
inline constexpr std::int32_t lie_visible = -1;   ///< The ray reached the light.
inline constexpr std::int32_t lie_no_light = -2;  ///< The light cannot contribute there: no ray.

/// How samples change a cell: `lists`: keep blocker lists (false: three states, §4.7);
/// `early_blockers`: keep what blocked a light before a sample saw it (false: Fig. 3.2 as drawn).
struct LieRules {
    bool lists = true;           ///< Keep blocker lists (false: three states, §4.7).
    bool early_blockers = true;  ///< Keep blockers met while a light is absent (false: Fig. 3.2 as drawn).
};

/// A light of a frozen cell: its blockers are blocker ids [begin, begin+count); `masked`: the
/// cell's masking drops it.
struct LieEntry {
    std::uint32_t light = 0;            ///< Index of the light in Lie::lights().
    LieState state = LieState::absent;  ///< Unoccluded or partial (absent lights get no entry).
    bool masked = false;                ///< The cell's masking (§3.2) drops this light.
    /// First of the entry's blocker ids in Lie::all_blocker_triangles().
    std::uint32_t blocker_begin = 0, blocker_count = 0;  ///< Number of its blockers (0 unless partial with lists).
};

/// A cell under construction.
template <Scalar T>
class LieCellBuilder {
public:
    /// An empty cell over `lights` lights, each absent.
    explicit LieCellBuilder(std::size_t lights)
        : state_(lights, LieState::absent), blocked_(lights, false), blockers_(lights), max_(lights, T(0)) {}

    /// Applies one sample's outcomes (per light) and contributions (0 where blocked). Returns the
    /// longest blocker list of a present light after it.
    std::size_t add_sample(std::span<const std::int32_t> outcome, std::span<const T> contribution, const LieRules& rules) {
        T total = 0;
        std::size_t longest = 0;
        for (std::size_t j = 0; j < state_.size(); ++j) {
            total += contribution[j];
            max_[j] = std::max(max_[j], contribution[j]);
            step(j, outcome[j], rules);
            if (state_[j] != LieState::absent) longest = std::max(longest, blockers_[j].size());
        }
        min_total_ = std::min(min_total_, total);
        ++samples_;
        return longest;
    }

    /// Light j's state so far.
    LieState state(std::size_t j) const { return state_[j]; }
    /// Light j's blocker list so far (triangle indices, in the order first met).
    const std::vector<std::uint32_t>& blockers(std::size_t j) const { return blockers_[j]; }
    /// Light j's largest contribution over the samples (luminance, visibility included).
    T max_contribution(std::size_t j) const { return max_[j]; }
    /// Smallest total luminance of the samples; 0 before any sample.
    T min_total() const { return samples_ ? min_total_ : T(0); }
    /// Samples applied so far.
    std::uint32_t samples() const { return samples_; }

    /// The cell's lights in light order (so that a sum over them rounds as a sum over all
    /// lights does), those masking drops flagged; appends their blocker lists to `blockers` and
    /// returns the masked count in `masked`.
    std::vector<LieEntry> freeze(T mask_fraction, std::vector<std::uint32_t>& blockers, std::uint32_t& masked) const {
        std::vector<std::uint32_t> dim;
        for (std::uint32_t j = 0; j < state_.size(); ++j)
            if (state_[j] != LieState::absent) dim.push_back(j);
        std::stable_sort(dim.begin(), dim.end(), [&](std::uint32_t a, std::uint32_t b) { return max_[a] < max_[b]; });
        const T budget = mask_fraction * min_total();
        T dropped = 0;
        std::size_t m = 0;
        while (m < dim.size() && dropped + max_[dim[m]] <= budget) dropped += max_[dim[m++]];
        std::vector<bool> is_masked(state_.size(), false);
        for (std::size_t i = 0; i < m; ++i) is_masked[dim[i]] = true;
        std::vector<LieEntry> out;
        for (std::uint32_t j = 0; j < state_.size(); ++j) {
            if (state_[j] == LieState::absent) continue;
            out.push_back({j, state_[j], is_masked[j], std::uint32_t(blockers.size()), std::uint32_t(blockers_[j].size())});
            blockers.insert(blockers.end(), blockers_[j].begin(), blockers_[j].end());
        }
        masked = std::uint32_t(m);
        return out;
    }

private:
    void step(std::size_t j, std::int32_t o, const LieRules& rules) {
        if (o == lie_no_light) return;
        LieState& s = state_[j];
        auto& list = blockers_[j];
        if (o == lie_visible) {
            if (s == LieState::absent) s = blocked_[j] ? LieState::partial : LieState::unoccluded;
            return;
        }
        if (s == LieState::absent && !rules.early_blockers) return;  // Fig. 3.2: blocker forgotten
        blocked_[j] = true;
        if (s != LieState::absent) s = LieState::partial;
        if (rules.lists && std::find(list.begin(), list.end(), std::uint32_t(o)) == list.end()) list.push_back(std::uint32_t(o));
    }

    std::vector<LieState> state_;
    std::vector<bool> blocked_;  // a sample was blocked (kept while absent only with early_blockers)
    std::vector<std::vector<std::uint32_t>> blockers_;
    std::vector<T> max_;
    T min_total_ = std::numeric_limits<T>::infinity();
    std::uint32_t samples_ = 0;
};

}  // namespace glint
