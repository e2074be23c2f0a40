//! Decompressing one scan-line block of a part whose channels may be subsampled.

use exr::compression::Compression;
use exr::math::Vec2;
use exr::meta::attribute::{ChannelList, IntegerBounds, SampleType};
use exr::meta::header::Header;
use exr::prelude::SmallVec;

use super::{At, Error, Layout, guard};

/// Decompresses one block of `lines` lines starting `rel_y` lines below the data
/// window's top; returns each channel's samples in the block, row-major.
pub(super) fn decode_block(
    scratch: &mut Header,
    layout: &Layout,
    compressed: Vec<u8>,
    rel_y: usize,
    lines: usize,
    at: At,
) -> Result<Vec<Vec<u32>>, Error> {
    let counts: Vec<usize> = layout
        .channels
        .iter()
        .map(|c| layout.lines_of(c, at.y, lines))
        .collect();
    let size: usize = layout
        .channels
        .iter()
        .zip(&counts)
        .map(|(c, n)| c.width * n * c.bytes)
        .sum();
    if compressed.len() == size {
        // Stored raw: compressing did not make it smaller.
        return Ok(split_lines(
            &compressed,
            layout,
            at.y,
            lines,
            u16::from_le_bytes,
            u32::from_le_bytes,
        ));
    }
    if compressed.len() > size {
        return Err(at.damaged(format!(
            "it holds {} bytes, more than its {size} uncompressed",
            compressed.len()
        )));
    }
    let compression = layout.compression;
    match compression {
        Compression::Uncompressed => {
            return Err(at.damaged(format!(
                "it holds {} bytes, not its {size} uncompressed",
                compressed.len()
            )));
        }
        Compression::B44 | Compression::B44A => {
            return decode_b44(scratch, layout, &compressed, &counts, at);
        }
        Compression::PIZ | Compression::DWAA(_) | Compression::DWAB(_) => {
            // These size each channel's plane as the block's size over the sampling
            // factors, true only when the block starts and ends on sampled lines.
            let aligned = layout
                .channels
                .iter()
                .all(|c| at.y % c.sampling.1 as i64 == 0 && lines.is_multiple_of(c.sampling.1));
            if !aligned {
                return Err(at.unsupported(format!(
                    "{compression} with blocks that split a channel's y sampling"
                )));
            }
            if compression != Compression::PIZ {
                check_dwa_counts(&compressed, layout, &counts, size).map_err(|e| at.damaged(e))?;
            }
        }
        Compression::RLE | Compression::ZIP1 | Compression::ZIP16 | Compression::PXR24 => {}
        _ => return Err(at.unsupported(format!("{compression}"))),
    }
    let area = layout.width * lines;
    if !size.is_multiple_of(area) {
        return Err(at.unsupported(format!(
            "{compression} with this subsampling ({size} bytes for {area} pixels, not a whole number a pixel)"
        )));
    }
    // The crate expects `area * bytes_per_pixel` bytes; make that the subsampled size.
    scratch.channels.bytes_per_pixel = size / area;
    let section = IntegerBounds::new(Vec2(0, rel_y as i32), Vec2(layout.width, lines));
    let bytes = decompress(scratch, compression, compressed, section, at)?;
    if bytes.len() != size {
        return Err(at.damaged(format!(
            "it decompressed to {} bytes, not {size}",
            bytes.len()
        )));
    }
    Ok(split_lines(
        &bytes,
        layout,
        at.y,
        lines,
        u16::from_ne_bytes,
        u32::from_ne_bytes,
    ))
}

/// The crate's decompressor, its panics and errors turned into this module's errors. Its
/// output is in native byte order.
fn decompress(
    header: &Header,
    compression: Compression,
    compressed: Vec<u8>,
    section: IntegerBounds,
    at: At,
) -> Result<Vec<u8>, Error> {
    match guard(|| compression.decompress_image_section_from_le(header, compressed, section, false))
    {
        Err(panic) => Err(at.damaged(panic)),
        Ok(Err(exr::error::Error::NotSupported(what))) => {
            Err(at.unsupported(format!("{compression} data with {what}")))
        }
        Ok(Err(e)) => Err(at.damaged(e.to_string())),
        Ok(Ok(bytes)) => Ok(bytes),
    }
}

/// A DWA block opens with eleven little-endian `u64` counters, from which the crate
/// sizes its buffers before it looks at the data: a damaged counter asked it for hundreds
/// of gigabytes, which aborts the process (no panic to catch). Sizes a valid block cannot
/// exceed are checked here first: byte sizes against a few times the block's size, sample
/// counts against its channels' planes padded to whole 8 × 8 DCT blocks.
fn check_dwa_counts(
    compressed: &[u8],
    layout: &Layout,
    counts: &[usize],
    size: usize,
) -> Result<(), String> {
    let counter = |i: usize| {
        compressed
            .get(i * 8..i * 8 + 8)
            .map_or(0, |b| u64::from_le_bytes(b.try_into().unwrap_or_default()))
    };
    let padded: usize = layout
        .channels
        .iter()
        .zip(counts)
        .map(|(c, &n)| (c.width + 7) * (n + 7))
        .sum();
    let (bytes, samples) = (4 * size as u64 + 1024, 2 * padded as u64 + 1024);
    // unknown uncompressed size, RLE uncompressed and raw sizes; AC and DC counts.
    for (index, limit) in [
        (1, bytes),
        (6, bytes),
        (7, bytes),
        (8, samples),
        (9, samples),
    ] {
        if counter(index) > limit {
            return Err(format!(
                "its DWA header claims {} bytes or samples, more than the block can hold",
                counter(index)
            ));
        }
    }
    Ok(())
}

/// Splits a decompressed block (lines, then channels, then samples) into each channel's
/// samples. `bytes` must hold exactly the block's size.
fn split_lines(
    bytes: &[u8],
    layout: &Layout,
    y0: i64,
    lines: usize,
    half: fn([u8; 2]) -> u16,
    word: fn([u8; 4]) -> u32,
) -> Vec<Vec<u32>> {
    let mut out: Vec<Vec<u32>> = layout.channels.iter().map(|_| Vec::new()).collect();
    let mut rest = bytes;
    for y in y0..y0 + lines as i64 {
        for (c, plane) in layout.channels.iter().zip(&mut out) {
            if y.rem_euclid(c.sampling.1 as i64) != 0 {
                continue;
            }
            let (line, tail) = rest.split_at(c.width * c.bytes);
            rest = tail;
            plane.extend(parse(line, c.bytes, half, word));
        }
    }
    out
}

fn parse<'a>(
    bytes: &'a [u8],
    size: usize,
    half: fn([u8; 2]) -> u16,
    word: fn([u8; 4]) -> u32,
) -> impl Iterator<Item = u32> + 'a {
    bytes.chunks_exact(size).map(move |s| match *s {
        [a, b] => u32::from(half([a, b])),
        [a, b, c, d] => word([a, b, c, d]),
        _ => 0,
    })
}

/// B44 stores each channel's plane in turn, in 4 × 4 blocks of 14 bytes (3 when flat);
/// non-half channels raw. The crate's B44 decoder sizes a subsampled channel's plane by
/// `sampling.area()` samples a pixel (`OpenEXR` uses one), so each half channel's bytes are
/// found here and decoded alone, as an unsampled plane of its own size.
fn decode_b44(
    scratch: &mut Header,
    layout: &Layout,
    compressed: &[u8],
    counts: &[usize],
    at: At,
) -> Result<Vec<Vec<u32>>, Error> {
    let mut rest = compressed;
    let mut out = Vec::with_capacity(layout.channels.len());
    for (c, &ny) in layout.channels.iter().zip(counts) {
        let nx = c.width;
        let short = || at.damaged(format!("its B44 data ends inside channel {:?}", c.name));
        if c.sample_type != SampleType::F16 {
            let (raw, tail) = rest.split_at_checked(nx * ny * c.bytes).ok_or_else(short)?;
            rest = tail;
            out.push(parse(raw, c.bytes, u16::from_le_bytes, u32::from_le_bytes).collect());
            continue;
        }
        if nx == 0 || ny == 0 {
            out.push(Vec::new());
            continue;
        }
        let mut len = 0;
        for _ in 0..nx.div_ceil(4) * ny.div_ceil(4) {
            len += if *rest.get(len + 2).ok_or_else(short)? >= 13 << 2 {
                3
            } else {
                14
            };
        }
        let (mine, tail) = rest.split_at_checked(len).ok_or_else(short)?;
        rest = tail;
        let mut data = mine.to_vec();
        if data.len() == nx * ny * 2 {
            // The crate reads data as long as the raw plane as stored raw; OpenEXR decides
            // that for the whole block, not a channel. A byte more (which B44 decoding
            // ignores) keeps the crate decoding.
            data.push(0);
        }
        let mut alone = c.description.clone();
        alone.sampling = Vec2(1, 1);
        scratch.channels = ChannelList::new(SmallVec::from_vec(vec![alone]));
        scratch.layer_size = Vec2(nx, ny);
        let bytes = decompress(
            scratch,
            layout.compression,
            data,
            IntegerBounds::new(Vec2(0, 0), Vec2(nx, ny)),
            at,
        )?;
        if bytes.len() != nx * ny * 2 {
            return Err(at.damaged(format!(
                "channel {:?} decompressed to {} bytes, not {}",
                c.name,
                bytes.len(),
                nx * ny * 2
            )));
        }
        out.push(parse(&bytes, 2, u16::from_ne_bytes, u32::from_ne_bytes).collect());
    }
    Ok(out)
}
