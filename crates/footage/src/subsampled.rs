//! Scan-line parts with subsampled channels.
//!
//! The `exr` crate refuses every file with a subsampled channel while it validates the
//! headers ("channel subsampling not supported yet"), which shuts out luminance/chroma
//! images: `Y` at full resolution, `RY` and `BY` at half resolution both ways. This module
//! reads such parts through the crate's lower layers instead: its header parser (with the
//! same checks, less that refusal), its offset tables, its scan-line blocks and its
//! decompressors; it lays every channel's samples out at the channel's own resolution.
//!
//! Inside a decompressed scan-line block, for each line `y` of the block, each channel
//! (in the header's order, sorted by name) that has a sample on that line
//! (`y % y_sampling == 0`, absolute coordinates) stores that line's `width / x_sampling`
//! samples, little-endian.
//!
//! Compression: none, RLE, ZIP (1 and 16 lines), PIZ, PXR24, B44, B44A, DWAA and DWAB
//! are read; HTJ2K (which the crate cannot decompress at all) is refused with
//! [`Error::Unsupported`]. The crate computes a block's size ignoring subsampling, so
//! blocks are handed to it with a header copy whose `bytes_per_pixel` makes that size
//! right; B44, whose decompressor mis-sizes subsampled channels, is handed one channel at
//! a time. Blocks stored raw (compression did not make them smaller) are read here.
//!
//! Damaged files are refused with an error: sizes are checked before anything is
//! allocated (at most [`MAX_PIXELS`] pixels and [`MAX_SAMPLES`] samples a part), channel
//! planes grow only as decompressed blocks arrive, and a panic inside the `exr` crate
//! (whose decompressors have panicked on fuzzed input) is caught and reported as an error.

use std::fs::File;
use std::io::{BufReader, Read};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use exr::block::chunk::CompressedScanLineBlock;
use exr::compression::Compression;
use exr::io::{PeekRead, Tracking};
use exr::math::Vec2;
use exr::meta::attribute::{ChannelDescription, SampleType};
use exr::meta::header::Header;
use exr::meta::{BlockDescription, MetaData, Requirements, magic_number};

mod decode;

/// The most pixels (data window width × height) [`read_part`] accepts in one part.
pub const MAX_PIXELS: usize = 1 << 28;

/// The most samples, over all channels at their own resolutions, [`read_part`] accepts
/// in one part.
pub const MAX_SAMPLES: usize = 1 << 29;

/// One channel's samples over the data window, at its own (subsampled) resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Samples {
    /// The channel's full name, layer prefix included (`"Y"`, `"RY"`, `"left.Y"`).
    pub name: String,
    /// How the samples are stored in the file.
    pub sample_type: SampleType,
    /// The channel's `(x, y)` sampling factors; `(1, 1)` when not subsampled.
    pub sampling: (usize, usize),
    /// Samples a row: the data window's width divided by the x sampling factor.
    pub width: usize,
    /// Rows: the data window's height divided by the y sampling factor.
    pub height: usize,
    /// `width * height` samples, row-major from the data window's top left: half-float
    /// bits widened to `u32`, `f32` bits, or the `u32` values themselves.
    pub bits: Vec<u32>,
}

/// Why a file or part could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be opened or read.
    #[error("cannot read the file: {0}")]
    Io(#[from] std::io::Error),
    /// The file's headers are damaged, or describe what no reader can read.
    #[error("damaged or unsupported EXR header: {0}")]
    Header(String),
    /// The file has fewer parts than the one asked for.
    #[error("the file has {count} part(s), so no part {part}")]
    NoSuchPart {
        /// The part asked for.
        part: usize,
        /// How many parts the file has.
        count: usize,
    },
    /// The part is valid but stored in a way this reader does not read.
    #[error("part {part}: {what} is not supported")]
    Unsupported {
        /// The part.
        part: usize,
        /// What is not supported.
        what: String,
    },
    /// The part's pixel data is damaged or too large.
    #[error("part {part}: {message}")]
    Damaged {
        /// The part.
        part: usize,
        /// What is wrong.
        message: String,
    },
    /// One scan-line block of the part is damaged.
    #[error("part {part}, block {block} (scan lines from y = {y}): {message}")]
    Block {
        /// The part.
        part: usize,
        /// The block's index in the part's offset table (increasing y).
        block: usize,
        /// The block's first scan line, in absolute coordinates.
        y: i64,
        /// What is wrong.
        message: String,
    },
}

/// The headers of every part of the file at `path`, checked as the `exr` crate checks
/// them (sane windows, chunk counts, attribute values), except that a scan-line part's
/// channels may be subsampled when their sampling factors divide the data window's
/// position and size. Deep and tiled parts are returned too (their channels must not be
/// subsampled).
///
/// # Errors
/// The file cannot be read, or its headers are damaged ([`Error::Header`]).
pub fn read_headers(path: &Path) -> Result<Vec<Header>, Error> {
    let mut read = open(path)?.0;
    Ok(read_meta(&mut read)?.headers.into_vec())
}

/// Every channel of scan-line part `part` of the file at `path`, in the header's order
/// (sorted by name), each at its own resolution; see [`Samples`].
///
/// # Errors
/// The file or part cannot be read: a deep or tiled part, an unsupported compression
/// ([`Error::Unsupported`]), damaged headers or pixel data, or a part larger than
/// [`MAX_PIXELS`] pixels or [`MAX_SAMPLES`] samples.
pub fn read_part(path: &Path, part: usize) -> Result<Vec<Samples>, Error> {
    let (mut read, file_len) = open(path)?;
    let meta = read_meta(&mut read)?;
    let count = meta.headers.len();
    let header = meta
        .headers
        .get(part)
        .ok_or(Error::NoSuchPart { part, count })?;
    let unsupported = |what: &str| Error::Unsupported {
        part,
        what: what.to_owned(),
    };
    if header.deep {
        return Err(unsupported("deep data"));
    }
    if header.blocks != BlockDescription::ScanLines {
        return Err(unsupported(
            "a tiled part (only scan-line parts are read here)",
        ));
    }
    let layout = Layout::of(header, part)?;

    // The offset tables: 8 bytes an entry, all of which the file must hold.
    let damaged = |message: String| Error::Damaged { part, message };
    let chunks = meta
        .headers
        .iter()
        .try_fold(0_usize, |sum, h| sum.checked_add(h.chunk_count));
    let tables_end = chunks
        .and_then(|c| c.checked_mul(8))
        .and_then(|bytes| bytes.checked_add(read.byte_position()))
        .filter(|&end| end as u64 <= file_len)
        .ok_or_else(|| damaged("the file is too short to hold its offset tables".to_owned()))?;
    let tables = guard(|| MetaData::read_offset_tables(&mut read, &meta.headers))
        .and_then(|r| r.map_err(|e| e.to_string()))
        .map_err(|e| damaged(format!("unreadable offset table: {e}")))?;
    let table = &tables[part];

    let mut scratch = header.clone();
    let mut planes: Vec<Vec<u32>> = layout.channels.iter().map(|_| Vec::new()).collect();
    for (block, &offset) in table.iter().enumerate() {
        let at = At {
            part,
            block,
            y: layout.y + (block * layout.lines_per_block) as i64,
        };
        let rel_y = block * layout.lines_per_block;
        let lines = layout.lines_per_block.min(layout.height - rel_y);
        if offset < tables_end as u64 || offset >= file_len {
            return Err(at.damaged(format!(
                "its offset {offset} lies outside the file's pixel data"
            )));
        }
        let compressed = read_chunk(&mut read, &meta, header, offset, file_len, part, at)?;
        let decoded = decode::decode_block(&mut scratch, &layout, compressed, rel_y, lines, at)?;
        for (plane, samples) in planes.iter_mut().zip(decoded) {
            plane.extend(samples);
        }
    }

    layout
        .channels
        .into_iter()
        .zip(planes)
        .map(|(channel, bits)| {
            if bits.len() == channel.width * channel.height {
                Ok(Samples {
                    name: channel.name,
                    sample_type: channel.sample_type,
                    sampling: channel.sampling,
                    width: channel.width,
                    height: channel.height,
                    bits,
                })
            } else {
                Err(damaged(format!(
                    "channel {:?} received {} samples, not its {} × {}",
                    channel.name,
                    bits.len(),
                    channel.width,
                    channel.height
                )))
            }
        })
        .collect()
}

type Reader = PeekRead<Tracking<BufReader<File>>>;

fn open(path: &Path) -> Result<(Reader, u64), Error> {
    let file = File::open(path)?;
    let len = file.metadata()?.len();
    Ok((PeekRead::new(Tracking::new(BufReader::new(file))), len))
}

/// Runs `f`, turning a panic into an error message. The `exr` crate's decoders have
/// panicked on fuzzed input (index arithmetic on corrupt sizes), and a damaged file must
/// give an error, never take the program down.
fn guard<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(ToString::to_string)
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        format!("the exr crate gave up on damaged data ({what})")
    })
}

/// Magic number, version flags and headers, then the checks of [`check_header`].
fn read_meta(read: &mut Reader) -> Result<MetaData, Error> {
    let meta = guard(|| -> exr::error::Result<MetaData> {
        magic_number::validate_exr(read)?;
        let requirements = Requirements::read(read)?;
        requirements.validate()?;
        // `true`: refuse damaged attribute values, as the crate's own image reader does.
        let headers = Header::read_all(read, &requirements, true)?;
        Ok(MetaData {
            requirements,
            headers,
        })
    })
    .map_err(Error::Header)?
    .map_err(|e| match e {
        exr::error::Error::Io(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => Error::Io(e),
        e => Error::Header(e.to_string()),
    })?;
    if meta.headers.is_empty() {
        return Err(Error::Header("no parts".to_owned()));
    }
    let multipart = meta.headers.len() > 1;
    for (index, header) in meta.headers.iter().enumerate() {
        guard(|| check_header(header, multipart))
            .and_then(|r| r)
            .map_err(|e| Error::Header(format!("part {index}: {e}")))?;
    }
    Ok(meta)
}

/// The crate's own header validation, run on a copy whose channels are not subsampled,
/// after checking the sampling factors as the crate would if it allowed them.
fn check_header(header: &Header, multipart: bool) -> Result<(), String> {
    let window = header.data_window();
    let flat_scan_lines = !header.deep && header.blocks == BlockDescription::ScanLines;
    for channel in &header.channels.list {
        let Vec2(sx, sy) = channel.sampling;
        if sx == 0 || sy == 0 {
            return Err(format!(
                "channel {:?} has a zero sampling factor",
                channel.name.to_string()
            ));
        }
        if (sx, sy) == (1, 1) {
            continue;
        }
        if !flat_scan_lines {
            return Err(format!(
                "channel {:?} is subsampled, which only flat scan-line parts allow",
                channel.name.to_string()
            ));
        }
        let divides = |position: i32, size: usize, s: usize| {
            i64::try_from(s).is_ok_and(|s| i64::from(position) % s == 0) && size.is_multiple_of(s)
        };
        if !divides(window.position.x(), window.size.x(), sx)
            || !divides(window.position.y(), window.size.y(), sy)
        {
            return Err(format!(
                "channel {:?}'s sampling ({sx}, {sy}) does not divide the data window (at {:?}, {:?} pixels)",
                channel.name.to_string(),
                window.position,
                window.size
            ));
        }
    }
    let mut unsampled = header.clone();
    for channel in &mut unsampled.channels.list {
        channel.sampling = Vec2(1, 1);
    }
    let mut long_names = false;
    unsampled
        .validate(multipart, &mut long_names, false)
        .map_err(|e| e.to_string())
}

/// One channel as stored.
struct ChannelLayout {
    name: String,
    description: ChannelDescription,
    sample_type: SampleType,
    sampling: (usize, usize),
    bytes: usize,
    width: usize,
    height: usize,
}

/// A part's geometry, checked against the size limits.
struct Layout {
    width: usize,
    height: usize,
    /// The data window's top, absolute.
    y: i64,
    lines_per_block: usize,
    compression: Compression,
    channels: Vec<ChannelLayout>,
}

impl Layout {
    fn of(header: &Header, part: usize) -> Result<Self, Error> {
        let Vec2(width, height) = header.layer_size;
        let too_large = |what: String| Error::Damaged {
            part,
            message: format!("{what}: more than this reader accepts"),
        };
        if width.checked_mul(height).is_none_or(|n| n > MAX_PIXELS) {
            return Err(too_large(format!(
                "a data window of {width} × {height} pixels"
            )));
        }
        let channels: Vec<ChannelLayout> = header
            .channels
            .list
            .iter()
            .map(|c| ChannelLayout {
                name: c.name.to_string(),
                description: c.clone(),
                sample_type: c.sample_type,
                sampling: (c.sampling.x(), c.sampling.y()),
                bytes: c.sample_type.bytes_per_sample(),
                width: width / c.sampling.x(),
                height: height / c.sampling.y(),
            })
            .collect();
        let samples: usize = channels.iter().map(|c| c.width * c.height).sum();
        if samples > MAX_SAMPLES {
            return Err(too_large(format!(
                "{samples} samples in {} channels",
                channels.len()
            )));
        }
        Ok(Self {
            width,
            height,
            y: i64::from(header.own_attributes.layer_position.y()),
            lines_per_block: header.compression.scan_lines_per_block(),
            compression: header.compression,
            channels,
        })
    }

    /// How many of the absolute lines `y0 .. y0 + lines` channel `c` has samples on.
    fn lines_of(&self, c: &ChannelLayout, y0: i64, lines: usize) -> usize {
        let s = c.sampling.1 as i64;
        let last = y0 + lines as i64 - 1;
        (last.div_euclid(s) - (y0 - 1).div_euclid(s)) as usize
    }
}

/// Where a block is, for its error messages.
#[derive(Clone, Copy)]
struct At {
    part: usize,
    block: usize,
    y: i64,
}

impl At {
    fn damaged(self, message: String) -> Error {
        Error::Block {
            part: self.part,
            block: self.block,
            y: self.y,
            message,
        }
    }

    fn unsupported(self, what: String) -> Error {
        Error::Unsupported {
            part: self.part,
            what,
        }
    }
}

/// The compressed bytes of the block at `offset`, after checking its part number and
/// first line; never more bytes than the block may hold or the file has left.
fn read_chunk(
    read: &mut Reader,
    meta: &MetaData,
    header: &Header,
    offset: u64,
    file_len: u64,
    part: usize,
    at: At,
) -> Result<Vec<u8>, Error> {
    let truncated = |e: &dyn std::fmt::Display| at.damaged(format!("unreadable block: {e}"));
    let position = usize::try_from(offset).map_err(|e| truncated(&e))?;
    read.skip_to(position).map_err(|e| truncated(&e))?;
    if meta.requirements.is_multilayer() {
        let mut bytes = [0; 4];
        read.read_exact(&mut bytes).map_err(|e| truncated(&e))?;
        let number = i32::from_le_bytes(bytes);
        if usize::try_from(number).ok() != Some(part) {
            return Err(at.damaged(format!("the block says it belongs to part {number}")));
        }
    }
    let left =
        usize::try_from(file_len.saturating_sub(read.byte_position() as u64)).unwrap_or(usize::MAX);
    let limit = header.max_block_byte_size().min(left);
    let block = guard(|| CompressedScanLineBlock::read(read, limit))
        .map_err(|e| truncated(&e))?
        .map_err(|e| truncated(&e))?;
    if i64::from(block.y_coordinate) != at.y {
        return Err(at.damaged(format!(
            "the block says it starts at y = {}",
            block.y_coordinate
        )));
    }
    Ok(block.compressed_pixels_le)
}
