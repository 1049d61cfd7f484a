// A live frame's display bytes (issue #40): the shaded frame packed to sRGB bytes on the GPU
// (display_pack.comp) straight into a read-back slot, then the AOVs and maps a frame asks for.
#include "core/stylize/stylizer_passes.h"

#include <cmath>

#include "core/gl/readback_ring.h"
#include "core/gl/shader_builder.h"

namespace volstyle::core::stylize {

void readBackDisplay(Frame& f, const DisplayReadback& display, StylizedFrame& out) {
    const StylizerTargets& t = f.targets;
    const Camera& cam = f.scene.camera;
    const int slot = display.ring->acquire(size_t(cam.width) * size_t(cam.height) * sizeof(uint32_t));
    try {
        layout::DisplayPackParams p;
        p.size = {cam.width, cam.height, 0, 0};
        p.scale.x = float(std::exp2(display.exposure));
        f.device.setParams(p);
        glUseProgram(f.device.program(gl::ShaderBuilder("display_pack.comp")).id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingImageOut, t.pixels.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, layout::kBindingDisplayOut, display.ring->buffer(slot).id());
        // 2D: a 4096² frame is 65,536 workgroups of 256 in one dimension, past GL's guaranteed 65,535.
        const int g = layout::kWorkgroup2D;
        glDispatchCompute(GLuint((cam.width + g - 1) / g), GLuint((cam.height + g - 1) / g), 1);
        out.displayBytes = display.ring->complete(slot);
        out.displaySlot = slot;
        StylizeSettings rest = f.settings;  // the AOVs and maps as asked; the frame is in the slot
        rest.pick.reset();
        if (rest.readAovs || rest.readShadowMaps) {
            Frame others{f.device, f.scene, rest, f.map, f.targets, {}, f.p};
            readBack(others, out);
            out.frame = Image();
        }
    } catch (...) {
        display.ring->release(slot);
        out.displayBytes = nullptr;
        out.displaySlot = -1;
        throw;
    }
}

}  // namespace volstyle::core::stylize
