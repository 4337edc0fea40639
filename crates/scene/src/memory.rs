//! How much memory a render needs, checked before anything is allocated: a film or an image
//! too large for the machine is refused with the figure, instead of aborting the process when
//! the allocation fails.

use crate::FilmDesc;

/// The machine's physical memory in bytes (`MemTotal` in /proc/meminfo), if known. A buffer
/// larger than this cannot be held; smaller ones may still not fit beside everything else,
/// but that is left to the system.
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// `bytes` as "1.5 GiB" (or "3.2e21 bytes" beyond exbibytes).
pub fn format_bytes(bytes: u128) -> String {
    const UNITS: [&str; 7] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else if v >= 1024.0 {
        format!("{:.1e} bytes", bytes as f64)
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}

/// Refuses a buffer of `bytes` for `what` that is larger than the machine's memory (or, where
/// that is unknown, than the address space).
pub fn check_fits(bytes: u128, what: &str) -> Result<(), String> {
    let limit = physical_memory().map_or(isize::MAX as u128, |m| m as u128);
    if bytes > limit {
        return Err(format!(
            "{what} needs {} of memory, more than this machine's {}",
            format_bytes(bytes),
            format_bytes(limit)
        ));
    }
    Ok(())
}

impl FilmDesc {
    /// Bytes a render holds per pixel of the film: the accumulated film (4 × f32), the
    /// developed image (3 × f32) and the encoded EXR (3 × f32, twice while it is written).
    pub const BYTES_PER_PIXEL: u64 = 16 + 12 + 2 * 12;

    /// Refuses a film whose buffers cannot fit in memory, or with more pixels than a `u32`
    /// counts (the renderer indexes pixels with one).
    pub fn check_size(&self) -> Result<(), String> {
        let pixels = self.width as u128 * self.height as u128;
        let what = format!("a {}x{} film", self.width, self.height);
        check_fits(pixels * Self::BYTES_PER_PIXEL as u128, &what)?;
        if pixels > u32::MAX as u128 {
            return Err(format!("{what} has more than 2^32 pixels"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_films_are_refused_with_the_figure() {
        let film = FilmDesc {
            width: 4_000_000_000,
            height: 4_000_000_000,
            ..FilmDesc::default()
        };
        let e = film.check_size().unwrap_err();
        assert!(
            e.contains("4000000000x4000000000 film needs 721.6 EiB"),
            "{e}"
        );
        assert!(FilmDesc::default().check_size().is_ok());
    }

    #[test]
    fn bytes_format() {
        assert_eq!(format_bytes(512), "512 bytes");
        assert_eq!(format_bytes(3 << 29), "1.5 GiB");
    }
}
