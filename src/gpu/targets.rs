//! Offscreen render targets: one shared colour target, the reference depth
//! and object ids, and one depth target per mode (so the error of every mode
//! of a frame can be measured in one pass after all of them have run).

use super::context::{GpuContext, GpuError};
use super::resolution::Resolution;

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
pub const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

pub struct RenderTargets {
    pub resolution: Resolution,
    /// The shaded picture every mode draws into (readable for pictures).
    pub color_texture: wgpu::Texture,
    pub color: wgpu::TextureView,
    pub reference_depth: wgpu::TextureView,
    pub reference_ids: wgpu::TextureView,
    pub mode_depths: Vec<wgpu::TextureView>,
}

/// A plain 2D texture of the viewport's size.
pub fn texture_2d(
    gpu: &GpuContext,
    label: &str,
    resolution: Resolution,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: resolution.width,
            height: resolution.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl RenderTargets {
    /// Whether the adapter can hold targets of `resolution` and what is read
    /// from them: each side within its texture limit, and a depth per pixel
    /// (the error measure's and the pictures' read-backs, 4 bytes a pixel)
    /// within its buffer limits. Checked before anything is drawn, so a
    /// resolution the flags accept cannot fail inside wgpu.
    pub fn check(gpu: &GpuContext, resolution: Resolution) -> Result<(), GpuError> {
        let limits = gpu.device.limits();
        let fits = |what, need: u64, limit: u64| {
            if need > limit {
                Err(GpuError::TooLarge { what, need, limit })
            } else {
                Ok(())
            }
        };
        let side = resolution.width.max(resolution.height);
        fits(
            "render target side",
            u64::from(side),
            u64::from(limits.max_texture_dimension_2d),
        )?;
        let depth_bytes = resolution.pixels() * 4;
        fits(
            "storage binding for a depth per pixel (bytes; a smaller --resolution fits)",
            depth_bytes,
            limits.max_storage_buffer_binding_size,
        )?;
        // Picture rows are padded to the copy alignment.
        let row = u64::from(resolution.width * 4).next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
        fits(
            "buffer for a picture read-back (bytes; a smaller --resolution fits)",
            depth_bytes.max(row * u64::from(resolution.height)),
            limits.max_buffer_size,
        )
    }

    pub fn new(gpu: &GpuContext, resolution: Resolution, modes: usize) -> RenderTargets {
        let texture = |label: &str, format, usage| texture_2d(gpu, label, resolution, format, usage);
        let sampled = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let view = |t: wgpu::Texture| t.create_view(&Default::default());
        let color_texture = texture(
            "color",
            COLOR_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        RenderTargets {
            resolution,
            color: color_texture.create_view(&Default::default()),
            color_texture,
            reference_depth: view(texture("reference depth", DEPTH_FORMAT, sampled)),
            reference_ids: view(texture("reference ids", ID_FORMAT, sampled)),
            mode_depths: (0..modes)
                .map(|i| view(texture(&format!("mode {i} depth"), DEPTH_FORMAT, sampled)))
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolutions_parse_and_reject_nonsense() {
        assert_eq!("800x600".parse(), Ok(Resolution::DEFAULT));
        assert_eq!("1X1".parse::<Resolution>().map(|r| r.pixels()), Ok(1));
        for bad in ["800", "0x600", "800x0", "-1x5", "axb", "9000x10", "800x600x2"] {
            assert!(bad.parse::<Resolution>().is_err(), "{bad}");
        }
    }
}
