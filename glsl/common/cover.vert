#version 450
// The pixels of one object, for a full-screen shading pass whose fragment shader needs only
// those (it reads the G-buffer at gl_FragCoord and discards every other material): an
// octagon circumscribing the circle along which the eye sees the object's bounding sphere
// touch its outline (src/technique/baseline/fullscreen.rs, `Cover`). A projection keeps
// containment, so its image contains the sphere's outline and so the object's. Six
// triangles fanned from corner 0. Its clip positions are divided by w here so that out_uv
// is interpolated affinely in screen space, exactly as common/fullscreen.vert's is; the pass
// draws this only while every corner is in front of the camera (w > 0).
#include "frame.glsl"
layout(push_constant) uniform CoverPushBlock { CoverPush pc; };
layout(location = 0) out vec2 out_uv;
const int FAN[18] = int[18](0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 5, 6, 0, 6, 7);
void main() {
    float a = float(FAN[gl_VertexIndex]) * (PI / 4.0);
    vec3 p = pc.centre.xyz + cos(a) * pc.u.xyz + sin(a) * pc.v.xyz;
    vec4 clip = frame.view_proj * vec4(p, 1.0);
    vec2 ndc = clip.xy / clip.w;
    // uv = (0, 0) at the top-left pixel corner, as in common/fullscreen.vert.
    out_uv = ndc * 0.5 + 0.5;
    // No depth test or write: any depth inside the clip volume.
    gl_Position = vec4(ndc, 0.5, 1.0);
}
