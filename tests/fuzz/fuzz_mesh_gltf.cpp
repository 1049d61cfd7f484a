// libFuzzer harness: an uploaded GLTF mesh (fuzz_mesh.h).
#include "fuzz_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) { return fuzzMesh(data, size, "gltf"); }
