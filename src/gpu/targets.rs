//! Offscreen render targets: one shared colour target, the reference depth
//! and object ids, and one depth target per mode (so the error of every mode
//! of a frame can be measured in one pass after all of them have run).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::context::{GpuContext, GpuError};

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
pub const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

/// Width × height in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Resolution {
    pub width: u32,
    pub height: u32,
}

/// Largest side accepted: beyond common texture limits and any use here.
const MAX_SIDE: u32 = 8192;

impl Resolution {
    /// The papers' resolution (003 and 004 measure at 800×600).
    pub const DEFAULT: Resolution = Resolution {
        width: 800,
        height: 600,
    };

    pub fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }

    pub fn pixels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }
}

impl FromStr for Resolution {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("resolution must be WIDTHxHEIGHT with sides in 1..={MAX_SIDE}, got '{s}'");
        let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let side = |v: &str| v.trim().parse::<u32>().ok().filter(|n| (1..=MAX_SIDE).contains(n));
        Ok(Resolution {
            width: side(w).ok_or_else(bad)?,
            height: side(h).ok_or_else(bad)?,
        })
    }
}

impl TryFrom<String> for Resolution {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl From<Resolution> for String {
    fn from(r: Resolution) -> String {
        r.to_string()
    }
}

impl fmt::Display for Resolution {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

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
