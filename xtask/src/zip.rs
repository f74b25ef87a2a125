//! A minimal ZIP writer for FMU archives: deflated entries, no directories entries, no
//! extras, 32-bit sizes (an FMU is a few megabytes). Enough for fmpy, FMI tools and `unzip`.

use flate2::Compression;
use flate2::write::DeflateEncoder;
use std::io::Write;

/// Files in the order they were added, each as (name, compressed data, CRC-32, size).
#[derive(Default)]
pub struct Zip {
    entries: Vec<(String, Vec<u8>, u32, u32)>,
}

impl Zip {
    /// Add `data` as `name` (a relative path with `/` separators).
    pub fn add(&mut self, name: &str, data: &[u8]) -> std::io::Result<()> {
        let mut e = DeflateEncoder::new(Vec::new(), Compression::best());
        e.write_all(data)?;
        let packed = e.finish()?;
        let size = u32::try_from(data.len())
            .map_err(|_| std::io::Error::other(format!("{name}: over 4 GiB")))?;
        self.entries
            .push((name.to_string(), packed, crc32fast::hash(data), size));
        Ok(())
    }

    /// The archive's bytes.
    pub fn finish(&self) -> Vec<u8> {
        // 1980-01-01 00:00, the DOS epoch: archives are reproducible.
        const TIME: u16 = 0;
        const DATE: u16 = 0x21;
        let mut out = Vec::new();
        let mut central = Vec::new();
        let u16le = |v: &mut Vec<u8>, x: u16| v.extend_from_slice(&x.to_le_bytes());
        let u32le = |v: &mut Vec<u8>, x: u32| v.extend_from_slice(&x.to_le_bytes());
        for (name, packed, crc, size) in &self.entries {
            let offset = out.len() as u32;
            u32le(&mut out, 0x0403_4b50);
            for x in [20, 0, 8, TIME, DATE] {
                u16le(&mut out, x);
            }
            for x in [*crc, packed.len() as u32, *size] {
                u32le(&mut out, x);
            }
            u16le(&mut out, name.len() as u16);
            u16le(&mut out, 0);
            out.extend_from_slice(name.as_bytes());
            out.extend_from_slice(packed);
            u32le(&mut central, 0x0201_4b50);
            // Made by UNIX (3), version 2.0; needs 2.0; no flags; deflate.
            for x in [0x0314, 20, 0, 8, TIME, DATE] {
                u16le(&mut central, x);
            }
            for x in [*crc, packed.len() as u32, *size] {
                u32le(&mut central, x);
            }
            for x in [name.len() as u16, 0, 0, 0, 0] {
                u16le(&mut central, x);
            }
            // External attributes: a regular file, rw-r--r--.
            u32le(&mut central, 0o100644 << 16);
            u32le(&mut central, offset);
            central.extend_from_slice(name.as_bytes());
        }
        let start = out.len() as u32;
        out.extend_from_slice(&central);
        u32le(&mut out, 0x0605_4b50);
        let n = self.entries.len() as u16;
        for x in [0, 0, n, n] {
            u16le(&mut out, x);
        }
        u32le(&mut out, central.len() as u32);
        u32le(&mut out, start);
        u16le(&mut out, 0);
        out
    }
}
