#version 450
// The pixels of one object, for a full-screen shading pass whose fragment shader needs only
// those (it reads the G-buffer at gl_FragCoord and discards every other material): a convex
// polyhedron around the object's bounding sphere (src/technique/baseline/fullscreen.rs,
// `Cover`), whose outline on screen contains the object's. Its clip positions are divided
// by w here so that out_uv is interpolated affinely in screen space, exactly as
// common/fullscreen.vert's is; valid only while every vertex is in front of the camera
// (w > 0), which the pass checks before it draws this instead of the full-screen triangle.
#include "frame.glsl"
layout(push_constant) uniform CoverPushBlock { CoverPush pc; };
layout(location = 0) in vec3 in_position;
layout(location = 0) out vec2 out_uv;
void main() {
    vec3 p = pc.sphere.xyz + pc.sphere.w * in_position;
    vec4 clip = frame.view_proj * vec4(p, 1.0);
    vec2 ndc = clip.xy / clip.w;
    // uv = (0, 0) at the top-left pixel corner, as in common/fullscreen.vert.
    out_uv = ndc * 0.5 + 0.5;
    // No depth test or write: any depth inside the clip volume.
    gl_Position = vec4(ndc, 0.5, 1.0);
}
