//! efsi's binary files — checkpoints ([`crate::checkpoint`]) and serialised FMU states — in one
//! format: a fixed prefix, then a serde value in [postcard]'s wire format.
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic: what the file is ([`Format::magic`], e.g. `EFSICKPT`) |
//! | 4 | format version, `u32` little-endian ([`Format::version`]) |
//! | 8 | length of the body in bytes, `u64` little-endian |
//! | 8 | [`checksum`] of the body, `u64` little-endian |
//! | … | the body: the value, postcard 1.0 (varint integers and lengths, `f64` as its 8 little-endian bytes, so values come back bit for bit) |
//!
//! The body's layout is the serde derive of the type the file holds: adding or reordering a
//! field is a new layout, and the [`Format::version`] of that file kind must be raised with it.
//! postcard is not self-describing, so a body is only ever read as the version it was written
//! as: the prefix — the same in every version, also those before this format — is read first
//! and a file of another version is refused naming its version ([`decode`]), never misread.
//! A truncated, padded or corrupted body fails its length or checksum test before it is
//! decoded; a body whose checksum holds but whose content does not fit the type (a file forged
//! or written by a faulty program) is refused by postcard with the reason.

use serde::Serialize;
use serde::de::DeserializeOwned;

/// The prefix's length in bytes (magic, version, length, checksum).
pub const PREFIX: usize = 28;

/// One kind of binary file: what its prefix must say.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Format {
    /// The first eight bytes of every file of this kind.
    pub magic: &'static [u8; 8],
    /// The version of the body's layout this efsi reads and writes.
    pub version: u32,
    /// What the file is, for messages (`checkpoint`, `serialised FMU state`).
    pub kind: &'static str,
}

/// The integrity check of a body: its 64-bit XXH3 hash.
pub fn checksum(body: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(body)
}

/// The bytes of a file of kind `format` holding `value`.
pub fn encode<T: Serialize + ?Sized>(format: &Format, value: &T) -> Vec<u8> {
    let mut out = Vec::with_capacity(4096);
    out.extend_from_slice(format.magic);
    out.extend_from_slice(&format.version.to_le_bytes());
    out.extend_from_slice(&[0; 16]);
    // Serialising to memory fails only for a type postcard cannot represent (a map of unknown
    // length, `deserialize_any`), which the types efsi writes are not: a failure is a bug.
    let mut out = postcard::to_extend(value, out).expect("postcard encodes efsi's file types");
    let body_len = (out.len() - PREFIX) as u64;
    let sum = checksum(&out[PREFIX..]);
    out[12..20].copy_from_slice(&body_len.to_le_bytes());
    out[20..28].copy_from_slice(&sum.to_le_bytes());
    out
}

/// The length of [`encode`]'s bytes of `value`, counted without making them.
pub fn encoded_len<T: Serialize + ?Sized>(value: &T) -> usize {
    let size = postcard::ser_flavors::Size::default();
    PREFIX
        + postcard::serialize_with_flavor(value, size).expect("postcard encodes efsi's file types")
}

/// The format version recorded in `bytes` when they start with `format`'s magic.
pub fn version_of(bytes: &[u8], format: &Format) -> Option<u32> {
    let version = bytes.get(8..12)?;
    (bytes.get(..8)? == format.magic)
        .then(|| u32::from_le_bytes(version.try_into().unwrap_or([0; 4])))
}

/// The value held in `bytes`, a file of kind `format`. The error says what is wrong: another
/// kind of file, another format version (named), a length or checksum that does not match, or
/// a body that is not a value of `T` (postcard's reason).
pub fn decode<T: DeserializeOwned>(bytes: &[u8], format: &Format) -> Result<T, String> {
    let magic = String::from_utf8_lossy(format.magic);
    let Some(version) = version_of(bytes, format) else {
        return Err(format!("not an efsi {} (no {magic} header)", format.kind));
    };
    let kind = format.kind;
    if version != format.version {
        let age = if version < format.version {
            "an earlier"
        } else {
            "a later"
        };
        return Err(format!(
            "{kind} format version {version} (written by {age} efsi); this efsi reads version {} only",
            format.version
        ));
    }
    if bytes.len() < PREFIX {
        return Err(format!(
            "{kind} truncated: {} bytes, shorter than the {PREFIX}-byte header",
            bytes.len()
        ));
    }
    let word = |k: usize| u64::from_le_bytes(bytes[k..k + 8].try_into().unwrap_or([0; 8]));
    let (len, sum) = (word(12), word(20));
    let body = &bytes[PREFIX..];
    if body.len() as u64 != len {
        return Err(format!(
            "{kind} truncated or padded: the header announces {len} bytes of data, the file has {}",
            body.len()
        ));
    }
    if checksum(body) != sum {
        return Err(format!("{kind} corrupted: the checksum does not match"));
    }
    let (value, rest) = postcard::take_from_bytes::<T>(body)
        .map_err(|e| format!("{kind} of version {version} whose data does not decode: {e}"))?;
    if !rest.is_empty() {
        return Err(format!(
            "{kind} with {} unexpected bytes after the data",
            rest.len()
        ));
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    const TEST: Format = Format {
        magic: b"EFSITEST",
        version: 3,
        kind: "test file",
    };

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Value {
        name: String,
        xs: Vec<f64>,
        maybe: Option<f64>,
    }

    fn value() -> Value {
        Value {
            name: "ρ".into(),
            xs: vec![0.1, -0.0, f64::MIN_POSITIVE, f64::NAN, 1e300],
            maybe: None,
        }
    }

    #[test]
    fn values_come_back_bit_for_bit() {
        let bytes = encode(&TEST, &value());
        assert_eq!(encoded_len(&value()), bytes.len());
        assert_eq!(&bytes[..8], b"EFSITEST");
        assert_eq!(version_of(&bytes, &TEST), Some(3));
        // Prefix, then: name (varint 2, 2 bytes), xs (varint 5, 40 bytes), None (1 byte).
        assert_eq!(bytes.len(), PREFIX + 1 + 2 + 1 + 40 + 1);
        let back: Value = decode(&bytes, &TEST).unwrap();
        assert_eq!(back.name, "ρ");
        let bits = |v: &Value| v.xs.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&value()));
        assert_eq!(back.maybe, None);
    }

    #[test]
    fn other_files_versions_and_damage_are_refused_with_the_reason() {
        let good = encode(&TEST, &value());
        let refused = |bytes: &[u8]| decode::<Value>(bytes, &TEST).unwrap_err();
        assert_eq!(
            refused(b"EFSICKPT\x04\0\0\0"),
            "not an efsi test file (no EFSITEST header)"
        );
        let mut old = good.clone();
        old[8] = 2;
        assert_eq!(
            refused(&old),
            "test file format version 2 (written by an earlier efsi); this efsi reads version 3 \
             only"
        );
        old[8] = 7;
        assert!(refused(&old).starts_with("test file format version 7 (written by a later efsi)"));
        assert_eq!(
            refused(&good[..good.len() - 1]),
            "test file truncated or padded: the header announces 45 bytes of data, the file has 44"
        );
        assert_eq!(
            refused(&good[..20]),
            "test file truncated: 20 bytes, shorter than the 28-byte header"
        );
        let mut flipped = good.clone();
        flipped[PREFIX + 10] ^= 1;
        assert_eq!(
            refused(&flipped),
            "test file corrupted: the checksum does not match"
        );
        // A body that passes its checksum but is not a value of the type.
        let mut forged = good[..PREFIX].to_vec();
        forged.extend_from_slice(&[9, b'a']);
        forged[12..20].copy_from_slice(&2u64.to_le_bytes());
        let sum = checksum(&forged[PREFIX..]);
        forged[20..28].copy_from_slice(&sum.to_le_bytes());
        assert!(
            refused(&forged).starts_with("test file of version 3 whose data does not decode: "),
            "{}",
            refused(&forged)
        );
        let mut padded = good.clone();
        padded.push(0);
        let n = (padded.len() - PREFIX) as u64;
        padded[12..20].copy_from_slice(&n.to_le_bytes());
        let sum = checksum(&padded[PREFIX..]);
        padded[20..28].copy_from_slice(&sum.to_le_bytes());
        assert_eq!(
            refused(&padded),
            "test file with 1 unexpected bytes after the data"
        );
    }
}
