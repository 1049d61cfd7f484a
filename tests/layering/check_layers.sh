#!/usr/bin/env bash
# The layers of docs/ARCHITECTURE.md, checked on every #include: server -> protocol -> core
# (values <- gl <- engines) -> core/base. CMake links enforce what links; this enforces what a
# file may even include, so a header cannot smuggle GL into protocol or HTTP into core.
set -uo pipefail
root="${1:-$(dirname "$0")/../..}"
cd "$root"
status=0

# The GL-free value headers of core (the volstyle_values target) that protocol may include.
values='core/base/|core/math/|core/image/image\.h|core/scene/|core/render/(curved_ray|curved_paths)\.h|core/shaders/layout\.h|core/volume/(volume|brick_layout|glass_sphere|basis)\.h|core/volume/resample\.h|core/stylize/(mesh|scene|tf_layers)\.h|core/translucent/(translucent_settings|perturbation)\.h'

# check FILES... -- ALLOWED_REGEX: every project include ("core/…", "protocol/…", "server/…") and
# every forbidden system header must match the allowed pattern.
check() {
  local what="$1" allowed="$2"
  shift 2
  for f in "$@"; do
    [ -f "$f" ] || continue
    while IFS= read -r inc; do
      if ! [[ "$inc" =~ ^($allowed) ]]; then
        echo "layering: $f includes \"$inc\" ($what)"
        status=1
      fi
    done < <(grep -oE '^#include "(core|protocol|server|cli)/[^"]+"' "$f" | sed -E 's/^#include "([^"]+)"/\1/')
  done
}

check "core/base depends on nothing" 'core/base/' core/base/*
check "core/gl depends only on core/base" 'core/base/|core/gl/' core/gl/*
check "value types are GL-free" "$values" core/math/* core/image/image.* core/scene/* core/render/curved_ray.* core/render/curved_paths.* \
  core/volume/volume.* core/volume/brick_layout.* core/volume/basis.h core/volume/resample.* core/stylize/mesh.* core/stylize/scene.* core/stylize/tf_layers.* core/translucent/translucent_settings.* core/translucent/perturbation.*
check "protocol sees only core's value types" "$values|protocol/" protocol/*.h protocol/*.cpp
check "core never includes protocol, server or the CLI" 'core/' $(find core -name '*.h' -o -name '*.cpp')
# Scene values (issue #36: camera, lighting, render settings, solve options) sit below every
# engine folder: they include only base, math, images, the volume's basis and the shared layout.
check "core/scene holds only values" 'core/base/|core/math/|core/image/image\.h|core/scene/|core/volume/basis\.h|core/shaders/layout\.h' core/scene/*
# Volumes sit below the engines: nothing in core/volume reaches up into the solver or a renderer
# (resample.h once included core/solve/solve_types.h for BasisType; issue #36).
check "core/volume depends only on base, math and the shared layout" 'core/base/|core/math/|core/volume/|core/shaders/layout\.h' core/volume/*

# The server's folders (issue #36): nothing but CMakeLists.txt at server/'s top; only server/http
# sees cpp-httplib; state, store, service and runtime never reach up into http; the runtime sits
# below sessions; the CLI meets the server only in serve_command.cpp (its `serve`), so the CLI
# library links no HTTP.
for f in server/*; do
  [ -d "$f" ] || [ "$f" = server/CMakeLists.txt ] || { echo "layering: $f sits at server/'s top; put it in http, service, state, store or runtime"; status=1; }
done
if grep -rlE '#include <httplib' server cli | grep -vE '^server/http/'; then echo "layering: cpp-httplib outside server/http"; status=1; fi
check "server/state, store and service never include server/http or the CLI" 'core/|protocol/|server/(state|store|service|runtime)/' $(find server/state server/store server/service -name '*.h' -o -name '*.cpp')
check "server/runtime sits below the session state" 'core/|protocol/|server/runtime/' $(find server/runtime -name '*.h' -o -name '*.cpp')
check "the CLI library sees the runtime, not the server's sessions or HTTP" 'core/|protocol/|cli/|server/runtime/' $(find cli -name '*.h' -o -name '*.cpp' | grep -vE '^cli/(serve_command|main)\.cpp$')

# The server, CLI and benchmarks see core's engines through GL-free headers only: no core/gl
# beyond the context's description, no kernel internals.
internal='core/gl/object\.h|core/gl/shader_builder\.h|core/render/(march_setup|derived_volumes|gl_convert)\.h|core/solve/(projector|gpu_vector|solver_state)\.h|core/shaders/'
# (bench/sparse_sampling_bench.cpp is the exception: it measures storage layouts below the
# engines — textures, buffers, a kernel of its own — to pick the one the engines will use, #39.)
for f in $(find server cli bench tests/http tests/cli -name '*.h' -o -name '*.cpp' | grep -v '^bench/sparse_sampling_bench\.cpp$'); do
  if grep -qE "^#include \"($internal)" "$f" || grep -qE '^#include <(epoxy|EGL)/' "$f"; then
    echo "layering: $f includes GL or a kernel's internals; use GpuDevice, GpuVolume, Renderer, Solver"; status=1
  fi
done
check "public engine headers are GL-free" 'core/base/|core/math/|core/image/image\.h|core/scene/|core/render/(gpu_volume|render_stats)\.h|core/gl/context\.h|core/gpu/|core/shaders/layout\.h|core/volume/volume\.h|core/stylize/(mesh|scene)\.h|core/translucent/(translucent_settings|perturbation)\.h' \
  core/gpu/gpu_device.h core/gpu/resource_cache.h core/render/gpu_volume.h core/render/renderer.h core/render/render_stats.h core/solve/solver.h core/solve/light_solver.h core/solve/combined_solve.h \
  core/stylize/stylizer.h core/translucent/translucent_renderer.h
for f in core/gpu/gpu_device.h core/gpu/resource_cache.h core/render/gpu_volume.h core/render/renderer.h core/solve/solver.h core/stylize/stylizer.h core/gl/context.h; do
  if grep -qE '^#include <(epoxy|EGL)/' "$f"; then echo "layering: $f is a public header and includes GL"; status=1; fi
done

# No HTTP or JSON in core; no GL in protocol.
if grep -rlE '#include <(httplib|nlohmann/)' core; then echo "layering: core includes HTTP or JSON headers"; status=1; fi
if grep -rlE '#include <(epoxy/|EGL/)' protocol; then echo "layering: protocol includes GL headers"; status=1; fi
# Raw GL object creation and deletion only in core/gl (STYLE: RAII owners).
if grep -rnE '\bgl(Gen|Create|Delete)(Textures|Buffers|Programs?|Shader|Samplers|Queries|Framebuffers|VertexArrays)\b' core server cli --include='*.cpp' --include='*.h' | grep -v '^core/gl/'; then
  echo "layering: raw glCreate*/glDelete* outside core/gl"; status=1
fi
[ $status -eq 0 ] && echo "layering: every include follows the layers"
exit $status
