//! # Test-only law library with a broken descriptor
//!
//! Written against the raw ABI of `efsi-law-abi` (no SDK), so that the loader's tests can see
//! each refusal. What is broken depends on the environment variable `EFSI_TEST_BAD_ABI`, read
//! when the descriptor is requested:
//!
//! * unset or `version` — `abi_version` is one more than the loader's (a version it does not
//!   know);
//! * `size` — the right version, but a `descriptor_size` 8 bytes too large;
//! * `v1-size` — version 1, which the loader also reads, but with version 2's descriptor size
//!   (a library whose layout does not match the version it claims);
//! * `functions` — right version and size, but no `create`/`destroy`/`evaluate_*` functions.
//!
//! Built as `libefsi_test_law_bad_abi.so`; loaded by path only.

use efsi_law_abi::{ABI_VERSION, DESCRIPTOR_SIZE, LawDescriptor, ParamDesc, v1};
use std::ffi::CStr;

const NAME: &CStr = c"test_bad_abi";
const DESCRIPTION: &CStr = c"test only: a descriptor the loader must refuse";

/// The entry point: a descriptor broken as `EFSI_TEST_BAD_ABI` says (leaked; test use only).
#[unsafe(no_mangle)]
pub extern "C" fn efsi_law_descriptor() -> *const LawDescriptor {
    std::panic::catch_unwind(|| {
        let mode = std::env::var("EFSI_TEST_BAD_ABI").unwrap_or_default();
        let (abi_version, descriptor_size) = match mode.as_str() {
            "size" => (ABI_VERSION, DESCRIPTOR_SIZE + 8),
            "v1-size" => (v1::ABI_VERSION, DESCRIPTOR_SIZE),
            "functions" => (ABI_VERSION, DESCRIPTOR_SIZE),
            _ => (ABI_VERSION + 1, DESCRIPTOR_SIZE),
        };
        let d = LawDescriptor {
            abi_version,
            descriptor_size,
            name: NAME.as_ptr(),
            description: DESCRIPTION.as_ptr(),
            param_count: 0,
            params: std::ptr::null(),
            param_desc_size: std::mem::size_of::<ParamDesc>(),
            create: None,
            destroy: None,
            evaluate_in_plane: None,
            evaluate_full: None,
        };
        Box::leak(Box::new(d)) as *const LawDescriptor
    })
    .unwrap_or(std::ptr::null())
}

const _: efsi_law_abi::EntryFn = efsi_law_descriptor;
