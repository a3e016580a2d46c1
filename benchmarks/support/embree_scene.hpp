// benchmarks/support/embree_scene.hpp: a triangle soup as an Embree 3 scene (one triangle
// geometry, vertices copied, built at the given quality), for the peer comparisons.
#pragma once

#ifdef GLINT_HAVE_EMBREE
#include <embree3/rtcore.h>

#include "tree_scenes.hpp"

namespace glint::bench {

/// A committed scene of `m`'s triangles on `device` (the caller releases it).
inline RTCScene embree_triangle_scene(RTCDevice device, const Mesh<float>& m, RTCBuildQuality quality) {
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, quality);
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, quality);
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * m.size()));
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.size()));
    for (std::size_t i = 0; i < m.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            for (int c = 0; c < 3; ++c) vb[9 * i + 3 * k + c] = m[i][k][c];
            ib[3 * i + k] = unsigned(3 * i + k);
        }
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scene);
    return scene;
}

}  // namespace glint::bench
#endif
