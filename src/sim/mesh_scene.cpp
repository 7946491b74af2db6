#include "lidarsurf/sim/mesh_scene.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <embree3/rtcore.h>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::sim {

struct MeshScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<Eigen::Vector3d> normals;  // per triangle
    std::vector<float> reflectivity;       // per triangle; empty when the mesh has no intensity

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

MeshScene::MeshScene(const Mesh& mesh) : impl_(std::make_unique<Impl>()) {
    mesh.check();
    if (mesh.triangles.empty()) throw InvalidInput("the scene mesh has no triangle");
    for (const auto& p : mesh.vertices)
        if (!p.allFinite()) throw InvalidInput("the scene mesh has a non-finite vertex");
    impl_->device = rtcNewDevice("verbose=0");
    if (!impl_->device) throw Error("Embree: cannot create a device");
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), mesh.vertices.size()));
    auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), mesh.triangles.size()));
    if (!v || !t) {
        rtcReleaseGeometry(geom);
        throw Error("Embree: cannot allocate the geometry buffers");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int a = 0; a < 3; ++a) v[3 * i + a] = static_cast<float>(mesh.vertices[i][a]);
    impl_->normals.reserve(mesh.triangles.size());
    if (!mesh.intensity.empty()) impl_->reflectivity.reserve(mesh.triangles.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        const auto& tri = mesh.triangles[i];
        for (int a = 0; a < 3; ++a) t[3 * i + a] = tri[a];
        const Eigen::Vector3d n = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]]).cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
        impl_->normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ());
        if (!mesh.intensity.empty()) impl_->reflectivity.push_back(mesh.intensity[tri[0]]);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(impl_->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(impl_->scene);
    if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE) throw Error("Embree: cannot build the scene");
}

MeshScene::~MeshScene() = default;
MeshScene::MeshScene(MeshScene&&) noexcept = default;
MeshScene& MeshScene::operator=(MeshScene&&) noexcept = default;

std::size_t MeshScene::triangle_count() const { return impl_->normals.size(); }

std::optional<RayHit> MeshScene::cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    rh.ray.org_x = static_cast<float>(o.x());
    rh.ray.org_y = static_cast<float>(o.y());
    rh.ray.org_z = static_cast<float>(o.z());
    rh.ray.dir_x = static_cast<float>(d.x());
    rh.ray.dir_y = static_cast<float>(d.y());
    rh.ray.dir_z = static_cast<float>(d.z());
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = static_cast<float>(max_range);
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || !(rh.ray.tfar > 0)) return std::nullopt;
    RayHit hit{rh.ray.tfar, rh.hit.primID, impl_->normals[rh.hit.primID]};
    if (!impl_->reflectivity.empty()) hit.reflectivity = impl_->reflectivity[rh.hit.primID];
    return hit;
}

std::optional<RayReturn> MeshScene::first_return(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range) const {
    const auto hit = cast(o, d, max_range);
    if (!hit) return std::nullopt;
    return RayReturn{hit->range, hit->reflectivity};
}

bool MeshScene::occluded(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const {
    const Eigen::Vector3d d = to - from;
    const double len = d.norm();
    if (len <= 0) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray{};
    const Eigen::Vector3d u = d / len;
    ray.org_x = static_cast<float>(from.x());
    ray.org_y = static_cast<float>(from.y());
    ray.org_z = static_cast<float>(from.z());
    ray.dir_x = static_cast<float>(u.x());
    ray.dir_y = static_cast<float>(u.y());
    ray.dir_z = static_cast<float>(u.z());
    ray.tnear = 0.0f;
    ray.tfar = static_cast<float>(len * (1.0 - 1e-4));  // the end point itself does not occlude
    ray.mask = 0xFFFFFFFFu;
    ray.flags = 0;
    rtcOccluded1(impl_->scene, &context, &ray);
    return ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace lidarsurf::sim
