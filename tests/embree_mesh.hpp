/* embree_mesh.hpp - one triangle mesh in an Embree 3 scene (one thread, robust mode), for the
   reference tests that cast rays against Embree (link -lembree3).
       em_scene s;  em_open(s, pos, nv, idx, nt);  ... rtcIntersect1(s.scene, ...) ...;  em_close(s); */
#ifndef TESTS_EMBREE_MESH_HPP
#define TESTS_EMBREE_MESH_HPP
#include <embree3/rtcore.h>

#include <cstdint>
#include <cstring>
#include <vector>

struct em_scene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<float> padded; /* Embree reads 16 bytes per vertex: one float of padding at the end */
};

static inline void em_open(em_scene &s, const float *pos, size_t nv, const uint32_t *idx, size_t nt)
{
    s.device = rtcNewDevice("threads=1");
    s.scene = rtcNewScene(s.device);
    rtcSetSceneFlags(s.scene, RTC_SCENE_FLAG_ROBUST);
    s.padded.assign(3 * nv + 1, 0.0f);
    std::memcpy(s.padded.data(), pos, 3 * nv * sizeof(float));
    RTCGeometry g = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s.padded.data(), 0, 3 * sizeof(float), nv);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, idx, 0, 3 * sizeof(uint32_t), nt);
    rtcCommitGeometry(g);
    rtcAttachGeometry(s.scene, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(s.scene);
}

static inline void em_close(em_scene &s)
{
    rtcReleaseScene(s.scene);
    rtcReleaseDevice(s.device);
    s.scene = nullptr;
    s.device = nullptr;
}
#endif
