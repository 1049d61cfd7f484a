// The environment's lobe basis (core/scene/environment_lobes.h): cells of equal solid angle,
// the projection of a lat-long map onto them, and the map written back from lobe radiances.
#include "core/scene/environment_lobes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/base/errors.h"

using namespace volstyle;
using namespace volstyle::core;

namespace {

constexpr double kPi = std::numbers::pi;

Image constantMap(int w, int h, Vec3d c) {
    Image img(w, h);
    for (size_t i = 0; i < img.pixelCount(); ++i)
        img.rgba[4 * i] = float(c.x), img.rgba[4 * i + 1] = float(c.y), img.rgba[4 * i + 2] = float(c.z), img.rgba[4 * i + 3] = 1;
    return img;
}

}  // namespace

TEST(EnvironmentLobes, CountsOutsideOneTo256AreRejected) {
    EXPECT_THROW(LobeBasis::make(0, LobeDomain::Sphere), InvalidArgument);
    EXPECT_THROW(LobeBasis::make(257, LobeDomain::Sphere), InvalidArgument);
    EXPECT_EQ(LobeBasis::make(1, LobeDomain::Sphere).size(), 1);
    EXPECT_EQ(LobeBasis::make(256, LobeDomain::UpperHemisphere).size(), 256);
}

TEST(EnvironmentLobes, CellsCoverTheDomainInNearlyEqualSolidAngles) {
    for (LobeDomain domain : {LobeDomain::Sphere, LobeDomain::UpperHemisphere})
        for (int n : {16, 64, 256}) {
            const LobeBasis b = LobeBasis::make(n, domain);
            const double total = domain == LobeDomain::Sphere ? 4 * kPi : 2 * kPi;
            double sum = 0;
            for (size_t i = 0; i < b.directions.size(); ++i) {
                EXPECT_NEAR(length(b.directions[i]), 1.0, 1e-12);
                if (domain == LobeDomain::UpperHemisphere) {
                    EXPECT_GT(b.directions[i].y, 0.0);
                }
            }
            for (double omega : b.solidAngles()) {
                sum += omega;
                // Fibonacci cells: within 25% of the mean over the sphere; over the hemisphere the
                // horizon cuts the lowest ring's cells (measured on a 512×256 grid).
                const double spread = domain == LobeDomain::Sphere ? 0.25 : 0.5;
                EXPECT_NEAR(omega, total / n, spread * total / n) << n;
            }
            EXPECT_NEAR(sum, total, 1e-9 * total);
        }
}

TEST(EnvironmentLobes, LatLongDirectionsFollowTheBackgroundConvention) {
    // −z at the image centre, +y on the top row, +x at u = 0.75.
    const Vec3d centre = latLongDirection(0.5, 0.5), top = latLongDirection(0.3, 0.0), right = latLongDirection(0.75, 0.5);
    EXPECT_NEAR(centre.z, -1.0, 1e-12);
    EXPECT_NEAR(top.y, 1.0, 1e-12);
    EXPECT_NEAR(right.x, 1.0, 1e-12);
    for (double u : {0.1, 0.4, 0.9})
        for (double v : {0.2, 0.5, 0.8}) {
            double u2, v2;
            latLongCoordinates(latLongDirection(u, v), u2, v2);
            EXPECT_NEAR(u2, u, 1e-12);
            EXPECT_NEAR(v2, v, 1e-12);
        }
}

TEST(EnvironmentLobes, AConstantMapProjectsToItsValue) {
    const LobeBasis b = LobeBasis::make(32, LobeDomain::Sphere);
    for (int w : {64, 1024}) {
        const auto c = projectEnvironment(b, constantMap(w, w / 2, {0.2, 0.5, 2.0}));
        for (const Vec3d& v : c) {
            EXPECT_NEAR(v.x, 0.2, 1e-5);
            EXPECT_NEAR(v.y, 0.5, 1e-5);
            EXPECT_NEAR(v.z, 2.0, 1e-5);
        }
    }
}

TEST(EnvironmentLobes, TheWrittenMapProjectsBackExactly) {
    for (LobeDomain domain : {LobeDomain::Sphere, LobeDomain::UpperHemisphere}) {
        const LobeBasis b = LobeBasis::make(48, domain);
        std::vector<Vec3d> radiance;
        for (int i = 0; i < b.size(); ++i) radiance.push_back({0.1 * i, 1.0 + std::sin(i), 3.0 - 0.05 * i});
        const Image map = lobesToLatLong(b, radiance, 512, 256);
        const auto back = projectEnvironment(b, map);
        for (int i = 0; i < b.size(); ++i) {
            EXPECT_NEAR(back[size_t(i)].x, radiance[size_t(i)].x, 1e-5) << i;
            EXPECT_NEAR(back[size_t(i)].y, radiance[size_t(i)].y, 1e-5) << i;
            EXPECT_NEAR(back[size_t(i)].z, radiance[size_t(i)].z, 1e-5) << i;
        }
        if (domain == LobeDomain::UpperHemisphere) {
            EXPECT_EQ(map.pixel(10, 200)[0], 0.0f);  // below the horizon
        }
    }
}

TEST(EnvironmentLobes, ProjectionKeepsTheMapsEnergy) {
    // ∫ L dω over the sphere equals Σ c_i Ω_i for any map (a weighted mean per cell).
    Image map(256, 128);
    double energy = 0;
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 256; ++x) {
            const Vec3d d = latLongDirection((x + 0.5) / 256, (y + 0.5) / 128);
            const float v = float(std::max(0.0, d.y) * 3 + 0.2 * (d.x > 0));
            float* p = map.pixel(x, y);
            p[0] = p[1] = p[2] = v, p[3] = 1;
            energy += v * 2 * kPi / 256 * (std::cos(kPi * y / 128) - std::cos(kPi * (y + 1) / 128));
        }
    const LobeBasis b = LobeBasis::make(64, LobeDomain::Sphere);
    const auto c = projectEnvironment(b, map);
    const auto omega = b.solidAngles();
    double sum = 0;
    for (size_t i = 0; i < c.size(); ++i) sum += c[i].x * omega[i];
    // The cells are measured on a 512-wide grid, the map is 256 wide: a cell's measured area and
    // the texels it got differ along its border.
    EXPECT_NEAR(sum, energy, 0.02 * energy);
}

TEST(EnvironmentLobes, NeighboursAreTheNearestOtherLobes) {
    const LobeBasis b = LobeBasis::make(64, LobeDomain::Sphere);
    const auto nb = b.neighbours(6);
    for (int i = 0; i < b.size(); ++i) {
        ASSERT_EQ(nb[size_t(i)].size(), 6u);
        double farthest = 2;
        for (int j : nb[size_t(i)]) {
            EXPECT_NE(j, i);
            farthest = std::min(farthest, dot(b.directions[size_t(i)], b.directions[size_t(j)]));
        }
        int closer = 0;
        for (int j = 0; j < b.size(); ++j)
            if (j != i && dot(b.directions[size_t(i)], b.directions[size_t(j)]) > farthest + 1e-12) ++closer;
        EXPECT_LE(closer, 5);
    }
}
