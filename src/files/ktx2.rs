//! A writer of uncompressed KTX2 cube maps, RGBA16F (Khronos KTX File Format 2.0): what Bevy's
//! `EnvironmentMapLight` and other engines load as they are. No crate writes KTX2; the container
//! is small: identifier, header, level index, one Basic Data Format Descriptor, key/values, then
//! the levels, smallest first. Tests read it back with the `ktx2` crate.

use super::export::LinearImage;

/// VK_FORMAT_R16G16B16A16_SFLOAT.
pub const VK_FORMAT_R16G16B16A16_SFLOAT: u32 = 97;

const IDENTIFIER: [u8; 12] = [0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A];

/// The Basic Data Format Descriptor of linear RGBA16F (KDF 1.3, section 5): RGBSDA colour model,
/// BT.709 primaries, linear transfer, four 16-bit signed float samples.
fn dfd() -> Vec<u8> {
    let mut block = Vec::new();
    let push = |v: &mut Vec<u8>, x: u32| v.extend_from_slice(&x.to_le_bytes());
    let samples = 4u32;
    let block_size = 24 + 16 * samples;
    // vendorId 0 (Khronos), descriptorType 0 (basic).
    push(&mut block, 0);
    // versionNumber 2, descriptorBlockSize.
    push(&mut block, 2 | (block_size << 16));
    // colorModel 1 (RGBSDA), colorPrimaries 1 (BT709), transferFunction 1 (linear), flags 0.
    push(&mut block, 1 | (1 << 8) | (1 << 16));
    // texelBlockDimension 0..3 = 1x1x1x1 (stored minus one), bytesPlane0 = 8.
    push(&mut block, 0);
    push(&mut block, 8);
    push(&mut block, 0);
    for (i, channel) in [0u32, 1, 2, 15].into_iter().enumerate() {
        // bitOffset, bitLength - 1, channelType with the float (0x80) and signed (0x40) bits.
        push(&mut block, (16 * i as u32) | (15 << 16) | ((channel | 0x80 | 0x40) << 24));
        // samplePosition 0, sampleLower -1.0f, sampleUpper 1.0f (float formats).
        push(&mut block, 0);
        push(&mut block, 0xBF80_0000);
        push(&mut block, 0x3F80_0000);
    }
    let mut out = Vec::new();
    push(&mut out, 4 + block.len() as u32);
    out.extend(block);
    out
}

/// Key/value data: each entry its length, the key and value (NUL-terminated), padding to 4.
fn key_values(pairs: &[(&str, &str)]) -> Vec<u8> {
    let mut out = Vec::new();
    for (k, v) in pairs {
        let mut kv = Vec::new();
        kv.extend_from_slice(k.as_bytes());
        kv.push(0);
        kv.extend_from_slice(v.as_bytes());
        kv.push(0);
        out.extend_from_slice(&(kv.len() as u32).to_le_bytes());
        out.extend(kv);
        while out.len() % 4 != 0 {
            out.push(0);
        }
    }
    out
}

fn level_bytes(faces: &[LinearImage]) -> Vec<u8> {
    let mut out = Vec::new();
    for face in faces {
        for p in face.pixels() {
            for c in p.0 {
                out.extend_from_slice(&half::f16::from_f32(c).to_bits().to_le_bytes());
            }
        }
    }
    out
}

/// The direction through texel (`x`, `y`) of face `face` (+X, -X, +Y, -Y, +Z, -Z) of a cube map
/// as Vulkan, OpenGL and so every engine sample it (the Vulkan specification's cube map face
/// selection table; rows top down).
pub fn vulkan_texel_direction(face: usize, x: u32, y: u32, size: u32) -> glam::Vec3 {
    let s = (x as f32 + 0.5) / size as f32 * 2.0 - 1.0;
    let t = (y as f32 + 0.5) / size as f32 * 2.0 - 1.0;
    let d = match face {
        0 => [1.0, -t, -s],
        1 => [-1.0, -t, s],
        2 => [s, 1.0, t],
        3 => [s, -1.0, -t],
        4 => [s, -t, 1.0],
        _ => [-s, -t, -1.0],
    };
    glam::Vec3::from_array(d).normalize()
}

/// Six faces of [`super::export::CUBE_FACES`] (images as a camera inside sees them) laid out as
/// the Vulkan cube map faces: the same texels, mirrored or turned. With `mirror_z` the texel a
/// direction (x, y, z) samples holds the sky towards (x, y, -z), for engines that sample cube maps
/// so (Bevy looks up `vec3(R.xy, -R.z)`).
pub fn to_vulkan_faces(faces: &[LinearImage], mirror_z: bool) -> Vec<LinearImage> {
    let size = faces[0].width();
    (0..6)
        .map(|f| {
            LinearImage::from_fn(size, size, |x, y| {
                let d = vulkan_texel_direction(f, x, y, size);
                let d = if mirror_z { glam::Vec3::new(d.x, d.y, -d.z) } else { d };
                let (i, fx, fy) = super::export::cube_texel(d, size);
                *faces[i].get_pixel((fx as u32).min(size - 1), (fy as u32).min(size - 1))
            })
        })
        .collect()
}

/// A cube map with mip levels (`levels[l]` = six faces in the order +X, -X, +Y, -Y, +Z, -Z laid
/// out as Vulkan samples them ([`to_vulkan_faces`]), each half the size of the level above) as a
/// KTX2 file. `writer` names the program (KTXwriter).
pub fn cube_map_rgba16f(levels: &[Vec<LinearImage>], writer: &str) -> Vec<u8> {
    let size = levels[0][0].width();
    let dfd = dfd();
    let kvd = key_values(&[("KTXorientation", "rd"), ("KTXwriter", writer)]);
    let header_len = 12 + 9 * 4 + 4 * 4 + 2 * 8;
    let index_len = 24 * levels.len();
    let dfd_offset = header_len + index_len;
    let kvd_offset = dfd_offset + dfd.len();
    let mut data_start = kvd_offset + kvd.len();
    // Levels are aligned to lcm(texel block size 8, 4) = 8.
    data_start = data_start.div_ceil(8) * 8;
    let bytes: Vec<Vec<u8>> = levels.iter().map(|l| level_bytes(l)).collect();
    // Smallest level first in the file; the index lists level 0 first.
    let mut offsets = vec![0usize; levels.len()];
    let mut at = data_start;
    for l in (0..levels.len()).rev() {
        at = at.div_ceil(8) * 8;
        offsets[l] = at;
        at += bytes[l].len();
    }
    let mut out = Vec::with_capacity(at);
    out.extend_from_slice(&IDENTIFIER);
    let u32s = [VK_FORMAT_R16G16B16A16_SFLOAT, 2, size, size, 0, 0, 6, levels.len() as u32, 0];
    for v in u32s {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in [dfd_offset as u32, dfd.len() as u32, kvd_offset as u32, kvd.len() as u32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    // No supercompression global data.
    out.extend_from_slice(&0u64.to_le_bytes());
    out.extend_from_slice(&0u64.to_le_bytes());
    for (l, b) in bytes.iter().enumerate() {
        for v in [offsets[l] as u64, b.len() as u64, b.len() as u64] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out.extend(dfd);
    out.extend(kvd);
    for l in (0..levels.len()).rev() {
        out.resize(offsets[l], 0);
        out.extend_from_slice(&bytes[l]);
    }
    out
}
