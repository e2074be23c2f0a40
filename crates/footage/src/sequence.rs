//! Frame sequences: frame numbers in paths, and frame ranges as Nuke and oiiotool write
//! them.
//!
//! **Patterns** in a path stand for the frame number, padded with zeros:
//! - `####` (Blender, Nuke): as many digits as `#`s (`f.####.exr` → `f.0007.exr`);
//! - `%04d` (Nuke, printf): `%0Nd` pads to N digits, `%d` not at all;
//! - `$F4` (Houdini): `$FN` pads to N digits, `$F` not at all.
//!
//! A negative frame keeps its sign in front of the digits (`-007`). A path with no pattern
//! is the same file for every frame.
//!
//! **Ranges** (`lumagraph render --frames`): `7`; `1-100` (both ends in); `1-100x2`
//! (every second frame: 1, 3, …, 99); `10-1` (backwards); several joined by commas
//! (`1-10,20,30-40x5`). Frames are rendered in the order written, each once.
//!
//! **On disk**: [`frames_on_disk`] lists the frames whose files exist for a pattern path
//! (the editor's frame range), reading each name back with [`frame_of`].

/// One frame-number pattern found in a text: where it is and how wide it pads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Pattern {
    start: usize,
    end: usize,
    width: usize,
}

/// The first pattern at or after byte `from`.
fn find(text: &str, from: usize) -> Option<Pattern> {
    let bytes = text.as_bytes();
    let mut i = from;
    while i < bytes.len() {
        match bytes[i] {
            b'#' => {
                let run = bytes[i..].iter().take_while(|&&b| b == b'#').count();
                return Some(Pattern {
                    start: i,
                    end: i + run,
                    width: run,
                });
            }
            b'%' => {
                let digits = bytes[i + 1..]
                    .iter()
                    .take_while(|b| b.is_ascii_digit())
                    .count();
                if bytes.get(i + 1 + digits) == Some(&b'd') {
                    let width = text[i + 1..i + 1 + digits].parse().unwrap_or(0);
                    return Some(Pattern {
                        start: i,
                        end: i + digits + 2,
                        width,
                    });
                }
            }
            b'$' if bytes.get(i + 1) == Some(&b'F') => {
                let digits = bytes[i + 2..]
                    .iter()
                    .take_while(|b| b.is_ascii_digit())
                    .count();
                // `$Frame` or `$FOO` are other variables, not the frame.
                let next = bytes.get(i + 2 + digits);
                if next.is_none_or(|b| !b.is_ascii_alphabetic() && *b != b'_') {
                    let width = text[i + 2..i + 2 + digits].parse().unwrap_or(0);
                    return Some(Pattern {
                        start: i,
                        end: i + digits + 2,
                        width,
                    });
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// Whether `text` holds a frame-number pattern.
pub fn has_pattern(text: &str) -> bool {
    find(text, 0).is_some()
}

/// `text` with every frame-number pattern replaced by `frame`, padded as it asks.
pub fn substitute(text: &str, frame: i64) -> String {
    let mut out = String::with_capacity(text.len() + 4);
    let mut at = 0;
    while let Some(p) = find(text, at) {
        out.push_str(&text[at..p.start]);
        let digits = format!("{:0width$}", frame.unsigned_abs(), width = p.width);
        if frame < 0 {
            out.push('-');
        }
        out.push_str(&digits);
        at = p.end;
    }
    out.push_str(&text[at..]);
    out
}

/// The frames of a range as [the module's doc](self) writes them, in order, each once.
///
/// # Errors
/// A malformed range or step, a step of 0, or more than a million frames; the message
/// shows what is expected.
pub fn parse_frames(spec: &str) -> Result<Vec<i64>, String> {
    const MAX: usize = 1_000_000;
    let expected = "expected frames as `7`, `1-100`, `1-100x2` or a comma-separated list of these";
    let mut frames = Vec::new();
    for item in spec.split(',').map(str::trim) {
        if item.is_empty() {
            return Err(format!("empty item in {spec:?}: {expected}"));
        }
        let (range, step) = match item.split_once(['x', 'X']) {
            Some((r, s)) => {
                let step: i64 = s.trim().parse().map_err(|_| {
                    format!("step {s:?} in {item:?} is not a whole number: {expected}")
                })?;
                if step <= 0 {
                    return Err(format!("step {step} in {item:?}: a step is 1 or more"));
                }
                (r.trim(), step)
            }
            None => (item, 1),
        };
        let (first, last) = split_range(range).ok_or_else(|| format!("{item:?}: {expected}"))?;
        let count = first.abs_diff(last) / step.unsigned_abs() + 1;
        if frames.len() as u64 + count > MAX as u64 {
            return Err(format!("{spec:?} has more than {MAX} frames"));
        }
        let dir = if last >= first { step } else { -step };
        let mut f = first;
        for _ in 0..count {
            if !frames.contains(&f) {
                frames.push(f);
            }
            f += dir;
        }
    }
    Ok(frames)
}

/// `A-B` (each maybe negative: `-5--1`) or a single `A`, as (first, last).
fn split_range(range: &str) -> Option<(i64, i64)> {
    if let Ok(single) = range.parse() {
        return Some((single, single));
    }
    // The dash that separates is the first one after a digit.
    let bytes = range.as_bytes();
    let at = (1..bytes.len()).find(|&i| bytes[i] == b'-' && bytes[i - 1].is_ascii_digit())?;
    let first = range[..at].trim().parse().ok()?;
    let last = range[at + 1..].trim().parse().ok()?;
    Some((first, last))
}

/// The frame `text` is of `template`: the number that [`substitute`] puts into
/// `template` to give `text` exactly (every pattern the same frame, padded as it asks:
/// `f.####.exr` takes `f.0007.exr` as 7 and `f.12345.exr` as 12345, but neither `f.7.exr`
/// nor `f.00007.exr`); `None` when no frame does, or `template` holds no pattern.
pub fn frame_of(template: &str, text: &str) -> Option<i64> {
    let first = find(template, 0)?;
    let rest = text.strip_prefix(template.get(..first.start)?)?;
    let sign = usize::from(rest.starts_with('-'));
    let digits = rest
        .get(sign..)?
        .bytes()
        .take_while(u8::is_ascii_digit)
        .count();
    // The longest run of digits first; a shorter one where the pattern is followed by
    // digits of the name (`####1.exr`).
    (1..=digits).rev().find_map(|n| {
        let frame: i64 = rest.get(..sign + n)?.parse().ok()?;
        (substitute(template, frame) == text).then_some(frame)
    })
}

/// The frames whose files exist for `path`, a path whose file name holds a frame
/// pattern: the files of its folder named as the pattern with a frame's number in its
/// place (as [`frame_of`] reads them), sorted, each once. An empty folder is the current
/// one; a file name without a pattern gives no frames.
///
/// # Errors
/// When the folder cannot be read, or when a folder's name holds the pattern (only the
/// file's name is searched).
pub fn frames_on_disk(path: &std::path::Path) -> std::io::Result<Vec<i64>> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = path.parent().unwrap_or_else(|| std::path::Path::new(""));
    if has_pattern(&dir.to_string_lossy()) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "{}: the frame pattern is in a folder's name; only file names are searched",
                path.display()
            ),
        ));
    }
    let dir = if dir.as_os_str().is_empty() {
        std::path::Path::new(".")
    } else {
        dir
    };
    let mut frames = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let frame = entry.file_name().to_str().and_then(|n| frame_of(&name, n));
        if let Some(frame) = frame
            && entry.path().is_file()
        {
            frames.push(frame);
        }
    }
    frames.sort_unstable();
    frames.dedup();
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pattern_pads_as_its_convention_says() {
        assert_eq!(substitute("f.####.exr", 7), "f.0007.exr");
        assert_eq!(substitute("f.#.exr", 123), "f.123.exr");
        assert_eq!(substitute("f.%04d.exr", 42), "f.0042.exr");
        assert_eq!(substitute("f.%d.exr", 42), "f.42.exr");
        assert_eq!(substitute("f.$F4.exr", 9), "f.0009.exr");
        assert_eq!(substitute("f.$F.exr", 9), "f.9.exr");
        assert_eq!(substitute("f.####.exr", -7), "f.-0007.exr");
        assert_eq!(substitute("a.##/b.####.exr", 3), "a.03/b.0003.exr");
        assert_eq!(substitute("f.####.exr", 12345), "f.12345.exr");
    }

    #[test]
    fn text_that_is_no_pattern_is_left_alone() {
        for text in [
            "plain.exr",
            "100%.png",
            "$HOME/a.exr",
            "$Frame.exr",
            "%x.exr",
            "a$F_b",
        ] {
            assert!(!has_pattern(text), "{text}");
            assert_eq!(substitute(text, 5), text);
        }
        assert!(has_pattern("f.$F4.exr"));
    }

    #[test]
    fn ranges_as_nuke_writes_them() {
        assert_eq!(parse_frames("7"), Ok(vec![7]));
        assert_eq!(parse_frames("1-3"), Ok(vec![1, 2, 3]));
        assert_eq!(parse_frames("1-10x3"), Ok(vec![1, 4, 7, 10]));
        assert_eq!(parse_frames("1-100x2").map(|f| f.len()), Ok(50));
        assert_eq!(parse_frames("3-1"), Ok(vec![3, 2, 1]));
        assert_eq!(parse_frames("-2-1"), Ok(vec![-2, -1, 0, 1]));
        assert_eq!(parse_frames("-5--3"), Ok(vec![-5, -4, -3]));
        assert_eq!(parse_frames("1-3, 2, 10"), Ok(vec![1, 2, 3, 10]));
    }

    #[test]
    fn malformed_ranges_say_what_is_expected() {
        for bad in ["", "a", "1-", "1-5x0", "1-5x-1", "1..5", "1,,2", "1-5xq"] {
            let e = parse_frames(bad).unwrap_err();
            assert!(!e.is_empty(), "{bad}");
        }
        assert!(parse_frames("1-2000000").unwrap_err().contains("more than"));
    }

    #[test]
    fn a_name_gives_back_the_frame_that_makes_it() {
        assert_eq!(frame_of("f.####.exr", "f.0007.exr"), Some(7));
        assert_eq!(frame_of("f.####.exr", "f.12345.exr"), Some(12345));
        assert_eq!(frame_of("f.####.exr", "f.-0007.exr"), Some(-7));
        assert_eq!(frame_of("f.%04d.exr", "f.0042.exr"), Some(42));
        assert_eq!(frame_of("f.$F.exr", "f.9.exr"), Some(9));
        assert_eq!(frame_of("a.##/b.####.exr", "a.03/b.0003.exr"), Some(3));
        assert_eq!(frame_of("f.####1.exr", "f.00071.exr"), Some(7));
        for wrong in [
            "f.7.exr",
            "f.00007.exr",
            "g.0007.exr",
            "f.0007.png",
            "f..exr",
        ] {
            assert_eq!(frame_of("f.####.exr", wrong), None, "{wrong}");
        }
        assert_eq!(frame_of("a.##/b.####.exr", "a.03/b.0004.exr"), None);
        assert_eq!(frame_of("plain.exr", "plain.exr"), None);
    }

    #[test]
    fn the_frames_on_disk_are_the_files_that_match() {
        let dir = std::env::temp_dir().join(format!("lumagraph-seq-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("s.0005.exr")).unwrap(); // a folder: not a frame
        for name in [
            "s.0003.exr",
            "s.0001.exr",
            "s.0010.exr",
            "s.1.exr",
            "t.0002.exr",
        ] {
            std::fs::write(dir.join(name), b"").unwrap();
        }
        assert_eq!(
            frames_on_disk(&dir.join("s.####.exr")).unwrap(),
            vec![1, 3, 10]
        );
        assert_eq!(frames_on_disk(&dir.join("s.#.exr")).unwrap(), vec![1]);
        assert!(frames_on_disk(&dir.join("u.####.exr")).unwrap().is_empty());
        assert!(frames_on_disk(&dir.join("x.##/s.####.exr")).is_err());
        assert!(frames_on_disk(&dir.join("missing/s.####.exr")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
