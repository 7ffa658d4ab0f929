//! The checker texture GLB files carry as their material's base colour, so the texture
//! coordinates are used (and seen): a viewer shows the parameterization as squares on the surface.

/// The texture's side in pixels (a power of two, so mipmaps need no resizing).
pub const SIDE: u32 = 256;
/// Squares per side.
pub const SQUARES: u32 = 16;

/// The colour of texel (x, y), y = 0 at the top (glTF's images start there; GLB texture
/// coordinates are written v-flipped to match): a checker whose light and dark squares are tinted
/// red along u and green along v, so the direction of each axis shows too.
pub fn texel(x: u32, y: u32) -> [u8; 3] {
    let u = (f64::from(x) + 0.5) / f64::from(SIDE);
    let v = 1.0 - (f64::from(y) + 0.5) / f64::from(SIDE);
    let square = SIDE / SQUARES;
    let light = ((x / square) + (y / square)).is_multiple_of(2);
    let level = if light { 1.0 } else { 0.55 };
    let channel = |c: f64| (255.0 * level * c).round().clamp(0.0, 255.0) as u8;
    [
        channel(0.45 + 0.5 * u),
        channel(0.45 + 0.5 * v),
        channel(0.75),
    ]
}

/// The texture as PNG bytes (RGB, 8 bits; the same bytes every time).
pub fn checker_png() -> std::io::Result<Vec<u8>> {
    let mut pixels = Vec::with_capacity((3 * SIDE * SIDE) as usize);
    for y in 0..SIDE {
        for x in 0..SIDE {
            pixels.extend(texel(x, y));
        }
    }
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, SIDE, SIDE);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(&pixels)
            .map_err(std::io::Error::other)?;
    }
    Ok(bytes)
}
