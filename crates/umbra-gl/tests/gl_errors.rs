//! GL errors are surfaced with the stage that caused them, never turned into a garbage image
//! (docs/catalogue.md §13: an unsized DEPTH_COMPONENT with a wrong type is an INVALID_ENUM or
//! INVALID_OPERATION on GLES, and the harness must say so).
#![allow(unsafe_code)]

use glow::HasContext;
use umbra_gl::Api;
use umbra_gl::render::Renderer;

#[test]
fn a_gl_error_names_its_stage_and_the_error() {
    let r = Renderer::new(Api::Gles3)
        .unwrap_or_else(|e| panic!("{} (`cargo xtask test` installs the Mesa packages)", e.0));
    assert!(r.check("clean").is_ok());
    let gl = r.gl();
    // SAFETY: a deliberately invalid but memory-safe call: no data pointer is passed.
    unsafe {
        let t = gl.create_texture().expect("texture");
        gl.bind_texture(glow::TEXTURE_2D, Some(t));
        gl.tex_image_2d(
            glow::TEXTURE_2D,
            0,
            glow::DEPTH_COMPONENT as i32,
            64,
            64,
            0,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_BYTE,
            glow::PixelUnpackData::Slice(None),
        );
        let err = r
            .check("shadow map storage")
            .expect_err("UNSIGNED_BYTE depth is invalid on GLES 3");
        let text = err.to_string();
        assert!(text.starts_with("shadow map storage: "), "{text}");
        assert!(
            text.contains("GL_INVALID_OPERATION") || text.contains("GL_INVALID_ENUM"),
            "{text}"
        );
        gl.delete_texture(t);
    }
    assert!(r.check("after").is_ok(), "errors are drained once reported");
}
