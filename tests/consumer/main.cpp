// Built against the *installed* glint package by tests/consumer/run.cmake.
#include <cstdio>

#include <glint/intersection/ivm.hpp>

int main() {
    const glint::Triangle<glint::Ivm<float>> tri({0, 0, 1}, {1, 0, 1}, {0, 1, 1});
    glint::TriangleHit<float> hit;
    const bool ok = tri.intersect(glint::Ray<float>{{0.25f, 0.25f, 0}, {0, 0, 1}}, hit) && hit.t == 1.0f;
    std::printf("consumer: installed glint %s\n", ok ? "works" : "FAILED");
    return ok ? 0 : 1;
}
