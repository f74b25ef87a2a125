//! Checking a law library's file before the dynamic loader maps it.
//!
//! `dlopen` trusts the file: it maps every loadable segment at the length its program header
//! declares and follows the dynamic table's addresses into them. A truncated library (a copy cut
//! short, a download interrupted) has segments that end past the end of the file, and touching
//! their pages raises SIGBUS; a corrupted header or dynamic table sends the loader through wild
//! addresses (SIGSEGV). Either kills the process — `efsi`, a Python interpreter, a sweep's
//! worker — before any error can be reported. So the file is read and checked first
//! ([`check_library_file`]), with the `object` crate's ELF reader:
//!
//! - the ELF header: magic, this machine's class (64-bit), byte order and architecture, a
//!   shared object (`ET_DYN`), the header's own size;
//! - the program header table, and every segment's bytes within the file; each loadable
//!   segment (`PT_LOAD`) no larger in the file than in memory, with an alignment that is a
//!   power of two and congruent file offset and address, and at least one of them;
//! - the dynamic table (`PT_DYNAMIC`): inside the file and inside a loadable segment's file
//!   bytes, ended by `DT_NULL`, no tag outside the defined ranges, each table with its size,
//!   entries of the standard sizes, the tables where the section headers (if any) put them,
//!   the relocations it counts relative (`DT_RELACOUNT`) relative; every table it points to
//!   (strings, symbols, hash tables, relocations, version tables, initialisers) inside a
//!   loadable segment's file bytes, with its declared size where the table declares one, and
//!   every string offset (`DT_NEEDED`, `DT_SONAME`, …) inside the string table;
//! - the relocations the loader applies (`DT_RELA`, `DT_REL`, `DT_JMPREL`): each target inside
//!   a loadable segment's memory, each symbol index inside the dynamic symbol table;
//! - the section header table, when there is one, and every section's bytes within the file;
//!   every section the program uses mapped where it was linked (its address and file offset
//!   in one loadable segment), executable or writable as it needs, and none of the data the
//!   program writes as it runs (`.data`, `.bss`) made read-only after relocation
//!   (`PT_GNU_RELRO`);
//! - the dynamic symbol table's names inside its string table, its defined symbols inside a
//!   loadable segment (functions and the initialiser in an executable one); the hash tables'
//!   chains inside the symbol table; relocations writing only to writable segments unless the
//!   library declares text relocations.
//!
//! Each structure is checked by a function of its own, in this order: the ELF header, the
//! program headers and segments, the dynamic table and the tables it points to, the section
//! headers and sections, the dynamic symbols, the hash chains, the relocations. The first
//! defect found is the error.
//!
//! What is checked is the file's structure; the machine code inside the segments is not (a
//! library whose code bytes are corrupted passes, as it would any loader's checks). The check
//! applies to ELF (Linux and the other ELF systems); elsewhere the platform's loader checks the
//! file alone.

use std::path::Path;

/// The largest law library read (1 GiB): the shipped laws are a few MB; a larger file is not a
/// law library, and reading it whole to check it would take that much memory.
pub const MAX_LIBRARY_BYTES: u64 = 1 << 30;

/// Why the file at `path` cannot be handed to the dynamic loader, if it cannot (see the module
/// docs): the defect, in words that name the table or segment.
pub fn check_library_file(path: &Path) -> Result<(), String> {
    let len = std::fs::metadata(path)
        .map_err(|e| format!("cannot read it: {e}"))?
        .len();
    if len > MAX_LIBRARY_BYTES {
        return Err(format!(
            "it has {len} bytes, more than a law library's limit of {MAX_LIBRARY_BYTES}"
        ));
    }
    let data = std::fs::read(path).map_err(|e| format!("cannot read it: {e}"))?;
    check_bytes(&data)
}

#[cfg(all(
    not(target_vendor = "apple"),
    not(windows),
    target_pointer_width = "64"
))]
fn check_bytes(data: &[u8]) -> Result<(), String> {
    imp::check(data)
}

#[cfg(not(all(
    not(target_vendor = "apple"),
    not(windows),
    target_pointer_width = "64"
)))]
fn check_bytes(_data: &[u8]) -> Result<(), String> {
    Ok(())
}

#[cfg(all(
    not(target_vendor = "apple"),
    not(windows),
    target_pointer_width = "64"
))]
mod imp {
    use object::elf::{self, FileHeader64};
    use object::read::elf::{Dyn as _, FileHeader, ProgramHeader, Rel as _, Rela as _};
    use object::read::elf::{SectionHeader as _, SectionTable, Sym as _};
    use object::{Endianness, pod};

    type Header = FileHeader64<Endianness>;
    type Segment = elf::ProgramHeader64<Endianness>;
    type Sections<'a> = SectionTable<'a, Header>;

    /// The ELF machine this build runs on (`None`: not checked).
    fn host_machine() -> Option<elf::Machine> {
        match std::env::consts::ARCH {
            "x86_64" => Some(elf::EM_X86_64),
            "aarch64" => Some(elf::EM_AARCH64),
            "riscv64" => Some(elf::EM_RISCV),
            "powerpc64" => Some(elf::EM_PPC64),
            "s390x" => Some(elf::EM_S390),
            "loongarch64" => Some(elf::EM_LOONGARCH),
            _ => None,
        }
    }

    /// A loadable segment: its address range in memory and the part backed by file bytes.
    struct Load {
        vaddr: u64,
        filesz: u64,
        memsz: u64,
        offset: u64,
        flags: u32,
    }

    impl Load {
        /// Whether `[addr, addr + size)` lies in the segment's file-backed bytes.
        fn holds_file(&self, addr: u64, size: u64) -> bool {
            addr >= self.vaddr
                && addr
                    .checked_add(size)
                    .is_some_and(|end| end <= self.vaddr + self.filesz)
        }
        /// Whether `[addr, addr + size)` lies in the segment's memory.
        fn holds_memory(&self, addr: u64, size: u64) -> bool {
            addr >= self.vaddr
                && addr
                    .checked_add(size)
                    .is_some_and(|end| end <= self.vaddr + self.memsz)
        }
        /// The file offset of address `addr` (which the segment's file bytes hold).
        fn file_offset(&self, addr: u64) -> u64 {
            self.offset + (addr - self.vaddr)
        }
    }

    /// The first loadable segment whose file bytes hold `[addr, addr + size)`.
    fn file_bytes(loads: &[Load], addr: u64, size: u64) -> Option<&Load> {
        loads.iter().find(|l| l.holds_file(addr, size))
    }

    /// The file being checked: its bytes and its ELF header, read in the header's byte order.
    struct Elf<'a> {
        data: &'a [u8],
        header: &'a Header,
        endian: Endianness,
    }

    impl Elf<'_> {
        /// The file's length in bytes.
        fn file_len(&self) -> u64 {
            self.data.len() as u64
        }
    }

    /// What the program headers declare: their table, the loadable segments (in table order),
    /// the dynamic table's segment (its index and header) and the read-only-after-relocation
    /// range (address, size).
    struct Segments<'a> {
        table: &'a [Segment],
        loads: Vec<Load>,
        dynamic: Option<(usize, &'a Segment)>,
        relro: Option<(u64, u64)>,
    }

    /// The dynamic table's entries before its `DT_NULL`.
    struct Dynamic<'a> {
        entries: &'a [elf::Dyn64<Endianness>],
        endian: Endianness,
    }

    impl Dynamic<'_> {
        /// The value of the first entry of tag `tag`.
        fn value(&self, tag: elf::DynamicTag) -> Option<u64> {
            self.entries
                .iter()
                .find(|d| d.tag(self.endian) == tag)
                .map(|d| d.val(self.endian))
        }
    }

    /// The tables the dynamic table points to, placed in the file: tag, file offset, size, and
    /// the end of the file bytes of the loadable segment that holds the table.
    struct Places(Vec<(elf::DynamicTag, u64, u64, u64)>);

    impl Places {
        /// The file offset, size and segment end of the table of tag `tag`, if placed.
        fn get(&self, tag: elf::DynamicTag) -> Option<(u64, u64, u64)> {
            self.0.iter().find(|p| p.0 == tag).map(|p| (p.1, p.2, p.3))
        }
    }

    /// Tables the loader reads, with the tag of their size where there is one.
    const TABLES: [(elf::DynamicTag, &str, Option<elf::DynamicTag>); 16] = [
        (elf::DT_STRTAB, "string table", Some(elf::DT_STRSZ)),
        (elf::DT_SYMTAB, "symbol table", None),
        (elf::DT_HASH, "hash table", None),
        (elf::DT_GNU_HASH, "GNU hash table", None),
        (
            elf::DT_RELA,
            "relocation table (RELA)",
            Some(elf::DT_RELASZ),
        ),
        (elf::DT_REL, "relocation table (REL)", Some(elf::DT_RELSZ)),
        (
            elf::DT_RELR,
            "relocation table (RELR)",
            Some(elf::DT_RELRSZ),
        ),
        (
            elf::DT_JMPREL,
            "PLT relocation table",
            Some(elf::DT_PLTRELSZ),
        ),
        (
            elf::DT_INIT_ARRAY,
            "initialiser array",
            Some(elf::DT_INIT_ARRAYSZ),
        ),
        (
            elf::DT_FINI_ARRAY,
            "finaliser array",
            Some(elf::DT_FINI_ARRAYSZ),
        ),
        (
            elf::DT_PREINIT_ARRAY,
            "pre-initialiser array",
            Some(elf::DT_PREINIT_ARRAYSZ),
        ),
        (elf::DT_VERSYM, "symbol version table", None),
        (elf::DT_VERDEF, "version definitions", None),
        (elf::DT_VERNEED, "version needs", None),
        (elf::DT_INIT, "initialiser", None),
        (elf::DT_FINI, "finaliser", None),
    ];

    /// The sections the linker makes for the dynamic table's tables: the tag of the table's
    /// address, the section's name, the tag of the table's size where there is one.
    const LINKED_SECTIONS: [(elf::DynamicTag, &str, Option<elf::DynamicTag>); 14] = [
        (elf::DT_INIT, ".init", None),
        (elf::DT_FINI, ".fini", None),
        (
            elf::DT_INIT_ARRAY,
            ".init_array",
            Some(elf::DT_INIT_ARRAYSZ),
        ),
        (
            elf::DT_FINI_ARRAY,
            ".fini_array",
            Some(elf::DT_FINI_ARRAYSZ),
        ),
        (
            elf::DT_PREINIT_ARRAY,
            ".preinit_array",
            Some(elf::DT_PREINIT_ARRAYSZ),
        ),
        (elf::DT_RELA, ".rela.dyn", Some(elf::DT_RELASZ)),
        (elf::DT_JMPREL, ".rela.plt", Some(elf::DT_PLTRELSZ)),
        (elf::DT_SYMTAB, ".dynsym", None),
        (elf::DT_STRTAB, ".dynstr", Some(elf::DT_STRSZ)),
        (elf::DT_GNU_HASH, ".gnu.hash", None),
        (elf::DT_HASH, ".hash", None),
        (elf::DT_VERSYM, ".gnu.version", None),
        (elf::DT_VERNEED, ".gnu.version_r", None),
        (elf::DT_VERDEF, ".gnu.version_d", None),
    ];

    /// The checks of the module docs, in their order; the first defect found is the error.
    pub(super) fn check(data: &[u8]) -> Result<(), String> {
        let elf = elf_header(data)?;
        let segments = program_headers(&elf)?;
        load_order(&segments.loads)?;
        placed_segments(&elf, &segments)?;
        let dynamic = dynamic_table(&elf, &segments)?;
        let loads = &segments.loads;
        dynamic_sizes(&dynamic)?;
        dynamic_tags(&dynamic)?;
        let places = table_places(&dynamic, loads)?;
        dynamic_strings(&dynamic)?;
        let sections = section_headers(&elf)?;
        let nsyms = dynamic_symbols(&elf, &sections, loads)?;
        init_and_fini(&dynamic, loads)?;
        placed_sections(&elf, &sections, &segments)?;
        tables_are_their_sections(&elf, &sections, &dynamic)?;
        version_counts(&elf, &sections, &dynamic)?;
        let nsyms = hash_chains(&elf, &places, nsyms)?;
        relocations(&elf, &dynamic, &places, loads, nsyms)?;
        relative_count(&elf, &dynamic, &places)
    }

    /// The ELF header: magic, class, byte order, file type, machine, the header's own size.
    fn elf_header(data: &[u8]) -> Result<Elf<'_>, String> {
        let len = data.len() as u64;
        if data.len() < 4 || &data[..4] != b"\x7fELF" {
            return Err("not an ELF shared library (no ELF magic number at its start)".into());
        }
        if data.get(4) != Some(&elf::ELFCLASS64.0) {
            return Err("an ELF file for 32-bit machines; efsi loads 64-bit libraries".into());
        }
        let header = Header::parse(data).map_err(|e| {
            format!("its ELF header is malformed or cut short ({e}; the file has {len} bytes)")
        })?;
        let endian = header
            .endian()
            .map_err(|e| format!("its ELF header is malformed ({e})"))?;
        if header.is_big_endian() != cfg!(target_endian = "big") {
            return Err("an ELF file of the other byte order than this machine's".into());
        }
        if header.e_type(endian) != elf::ET_DYN {
            return Err(format!(
                "not a shared library (ELF file type {}, a shared object is {})",
                header.e_type(endian).0,
                elf::ET_DYN.0
            ));
        }
        if let Some(m) = host_machine()
            && header.e_machine(endian) != m
        {
            return Err(format!(
                "built for another architecture (ELF machine {}, this machine is {} = {})",
                header.e_machine(endian).0,
                m.0,
                std::env::consts::ARCH
            ));
        }
        if usize::from(header.e_ehsize(endian)) != std::mem::size_of::<Header>() {
            return Err(format!(
                "its ELF header declares {} bytes, a 64-bit header has {}",
                header.e_ehsize(endian),
                std::mem::size_of::<Header>()
            ));
        }
        Ok(Elf {
            data,
            header,
            endian,
        })
    }

    /// The program header table inside the file, every segment's file bytes inside the file,
    /// each loadable segment sound, and at least one of them.
    fn program_headers<'a>(elf: &Elf<'a>) -> Result<Segments<'a>, String> {
        let (header, endian, len) = (elf.header, elf.endian, elf.file_len());
        let phdrs = header.program_headers(endian, elf.data).map_err(|e| {
            format!(
                "its program header table (at byte {}, {} entries) lies outside the file of {len} bytes ({e})",
                header.e_phoff(endian),
                header.e_phnum(endian)
            )
        })?;
        let mut loads = Vec::new();
        let mut dynamic = None;
        let mut relro = None;
        for (k, ph) in phdrs.iter().enumerate() {
            let (offset, filesz) = (ph.p_offset(endian), ph.p_filesz(endian));
            let end = offset.checked_add(filesz);
            if end.is_none_or(|e| e > len) {
                return Err(format!(
                    "segment {k} ({}) declares file bytes {offset}..{} but the file has {len} bytes: the file is truncated or its program headers are corrupted",
                    segment_kind(ph.p_type(endian)),
                    end.map_or_else(|| "∞".to_string(), |e| e.to_string()),
                ));
            }
            match ph.p_type(endian) {
                elf::PT_LOAD => loads.push(load_segment(k, ph, endian)?),
                elf::PT_DYNAMIC => dynamic = Some((k, ph)),
                elf::PT_GNU_RELRO => relro = Some((ph.p_vaddr(endian), ph.p_memsz(endian))),
                _ => {}
            }
        }
        if loads.is_empty() {
            return Err("it has no loadable segment".into());
        }
        Ok(Segments {
            table: phdrs,
            loads,
            dynamic,
            relro,
        })
    }

    /// Loadable segment `k`: no larger in the file than in memory, inside the address space,
    /// its alignment a power of two with congruent file offset and address.
    fn load_segment(k: usize, ph: &Segment, endian: Endianness) -> Result<Load, String> {
        let (offset, filesz) = (ph.p_offset(endian), ph.p_filesz(endian));
        let (vaddr, memsz, align) = (ph.p_vaddr(endian), ph.p_memsz(endian), ph.p_align(endian));
        if filesz > memsz {
            return Err(format!(
                "loadable segment {k} has {filesz} file bytes but only {memsz} in memory"
            ));
        }
        if vaddr.checked_add(memsz).is_none() {
            return Err(format!(
                "loadable segment {k} ends past the end of the address space"
            ));
        }
        if align > 1 && (!align.is_power_of_two() || vaddr % align != offset % align) {
            return Err(format!(
                "loadable segment {k}'s alignment {align} is not a power of two or does not fit its offset {offset} and address {vaddr:#x}"
            ));
        }
        Ok(Load {
            vaddr,
            filesz,
            memsz,
            offset,
            flags: ph.p_flags(endian).0,
        })
    }

    /// The loader reserves the span from the first loadable segment to the end of the last
    /// and maps each inside it: they must come in address order without overlapping.
    fn load_order(loads: &[Load]) -> Result<(), String> {
        for (k, w) in loads.windows(2).enumerate() {
            if w[1].vaddr < w[0].vaddr + w[0].memsz {
                return Err(format!(
                    "its loadable segments {k} and {} overlap or are out of address order",
                    k + 1
                ));
            }
        }
        Ok(())
    }

    /// The segments the loader finds through the loadable ones (`PT_PHDR`, `PT_GNU_RELRO`)
    /// inside them, and the thread-local data of a sane size.
    fn placed_segments(elf: &Elf<'_>, segments: &Segments<'_>) -> Result<(), String> {
        let (header, endian, loads) = (elf.header, elf.endian, &segments.loads);
        for (k, ph) in segments.table.iter().enumerate() {
            // The loader finds the program headers in memory by PT_PHDR, and protects the
            // PT_GNU_RELRO range read-only: both must be where the loadable segments put them.
            if ph.p_type(endian) == elf::PT_PHDR {
                let (addr, size) = (ph.p_vaddr(endian), ph.p_filesz(endian));
                let placed = loads.iter().any(|l| {
                    l.holds_file(addr, size) && l.file_offset(addr) == header.e_phoff(endian)
                });
                if !placed || ph.p_offset(endian) != header.e_phoff(endian) {
                    return Err(format!(
                        "its program header segment (segment {k}, address {addr:#x}) is not where a loadable segment maps the program headers"
                    ));
                }
            }
            if ph.p_type(endian) == elf::PT_GNU_RELRO {
                let (addr, size) = (ph.p_vaddr(endian), ph.p_memsz(endian));
                if !loads
                    .iter()
                    .any(|l| l.holds_memory(addr, size) && l.flags & elf::PF_W.0 != 0)
                {
                    return Err(format!(
                        "its read-only-after-relocation range (segment {k}, address {addr:#x}, {size} bytes) is not inside one writable loadable segment"
                    ));
                }
            }
            if ph.p_type(endian) == elf::PT_TLS
                && (ph.p_filesz(endian) > ph.p_memsz(endian) || ph.p_memsz(endian) > 1 << 30)
            {
                return Err(format!(
                    "its thread-local data (segment {k}) declares {} file bytes and {} in memory",
                    ph.p_filesz(endian),
                    ph.p_memsz(endian)
                ));
            }
        }
        Ok(())
    }

    /// The dynamic table: present, where a loadable segment's file bytes put it, readable,
    /// ended by `DT_NULL`.
    fn dynamic_table<'a>(elf: &Elf<'a>, segments: &Segments<'a>) -> Result<Dynamic<'a>, String> {
        let endian = elf.endian;
        let (k, dyn_ph) = segments
            .dynamic
            .ok_or("it has no dynamic table (PT_DYNAMIC)")?;
        let (dyn_addr, dyn_size) = (dyn_ph.p_vaddr(endian), dyn_ph.p_filesz(endian));
        match file_bytes(&segments.loads, dyn_addr, dyn_size) {
            Some(l) if l.file_offset(dyn_addr) == dyn_ph.p_offset(endian) => {}
            _ => {
                return Err(format!(
                    "its dynamic table (segment {k}, address {dyn_addr:#x}, {dyn_size} bytes) is not where a loadable segment puts it"
                ));
            }
        }
        let entries = dyn_ph
            .dynamic(endian, elf.data)
            .map_err(|e| format!("its dynamic table is malformed ({e})"))?
            .unwrap_or_default();
        let Some(n) = entries.iter().position(|d| d.tag(endian) == elf::DT_NULL) else {
            return Err("its dynamic table has no end (DT_NULL)".into());
        };
        Ok(Dynamic {
            entries: &entries[..n],
            endian,
        })
    }

    /// Each table with a size has its size (the loader reads it unchecked), entries of the
    /// standard sizes (it asserts them), version tables with the symbol versions, PLT
    /// relocations of a known kind.
    fn dynamic_sizes(dynamic: &Dynamic<'_>) -> Result<(), String> {
        let value = |tag| dynamic.value(tag);
        for (tag, what, size_tag) in TABLES {
            if let Some(size_tag) = size_tag
                && value(tag).is_some() != value(size_tag).is_some()
            {
                return Err(format!(
                    "its dynamic table gives the {what} without its size, or its size without \
                     it: the table is corrupted"
                ));
            }
        }
        if value(elf::DT_PLTREL).is_some() != value(elf::DT_JMPREL).is_some() {
            return Err(
                "its dynamic table gives the PLT relocations' kind without the table, or the \
                 table without its kind: the table is corrupted"
                    .into(),
            );
        }
        for (tag, what, size) in [
            (elf::DT_RELAENT, "RELA entries", 24),
            (elf::DT_RELENT, "REL entries", 16),
            (elf::DT_SYMENT, "symbols", 24),
            (elf::DT_RELRENT, "RELR entries", 8),
        ] {
            if let Some(v) = value(tag)
                && v != size
            {
                return Err(format!(
                    "its dynamic table declares {what} of {v} bytes, the format's are {size}"
                ));
            }
        }
        if (value(elf::DT_VERNEED).is_some() || value(elf::DT_VERDEF).is_some())
            && value(elf::DT_VERSYM).is_none()
        {
            return Err(
                "its dynamic table gives version tables without the symbol versions (DT_VERSYM)"
                    .into(),
            );
        }
        if let Some(v) = value(elf::DT_PLTREL)
            && v != elf::DT_RELA.0 as u64
            && v != elf::DT_REL.0 as u64
        {
            return Err(format!(
                "its dynamic table declares PLT relocations of kind {v}, neither RELA nor REL"
            ));
        }
        Ok(())
    }

    /// Each tag once, but for the lists, and no tag outside the defined ranges.
    fn dynamic_tags(dynamic: &Dynamic<'_>) -> Result<(), String> {
        let (entries, endian) = (dynamic.entries, dynamic.endian);
        // Each tag once (the loader keeps the last of a repeated one, this check the first),
        // but for the lists (needed libraries, filters).
        for (k, d) in entries.iter().enumerate() {
            let t = d.tag(endian);
            let list = [
                elf::DT_NEEDED,
                elf::DT_AUXILIARY,
                elf::DT_FILTER,
                elf::DT_POSFLAG_1,
            ];
            if !list.contains(&t) && entries[..k].iter().any(|e| e.tag(endian) == t) {
                return Err(format!(
                    "its dynamic table gives tag {:#x} twice: the table is corrupted",
                    t.0
                ));
            }
        }
        for d in entries {
            let t = d.tag(endian).0;
            // The loader files an entry by its tag's range (the GNU value, address and
            // version ranges, the processor's): a tag elsewhere in the OS range can land on
            // another table's slot.
            let known = (0..=elf::DT_RELRENT.0).contains(&t)
                || (0x6fff_fd00..=0x6fff_ffff).contains(&t)
                || (std::env::consts::ARCH != "x86_64" && (0x7000_0000..=0x7000_00ff).contains(&t))
                || (0x7fff_fffd..=0x7fff_ffff).contains(&t);
            if !known {
                return Err(format!(
                    "its dynamic table holds an entry of tag {t:#x}, outside every defined range: the table is corrupted"
                ));
            }
        }
        Ok(())
    }

    /// Every table the dynamic table points to inside a loadable segment's file bytes, with
    /// its declared size where it declares one.
    fn table_places(dynamic: &Dynamic<'_>, loads: &[Load]) -> Result<Places, String> {
        let mut places = Vec::new();
        for (tag, what, size_tag) in TABLES {
            let Some(addr) = dynamic.value(tag) else {
                continue;
            };
            let size = size_tag.and_then(|t| dynamic.value(t)).unwrap_or(1);
            match file_bytes(loads, addr, size) {
                Some(l) => places.push((tag, l.file_offset(addr), size, l.offset + l.filesz)),
                None => {
                    return Err(format!(
                        "its dynamic table puts the {what} at address {addr:#x} ({size} bytes), outside the file's loadable bytes: the file is truncated or corrupted"
                    ));
                }
            }
        }
        Ok(Places(places))
    }

    /// Every string offset of the dynamic table (`DT_NEEDED`, `DT_SONAME`, …) inside the
    /// string table.
    fn dynamic_strings(dynamic: &Dynamic<'_>) -> Result<(), String> {
        let endian = dynamic.endian;
        let strsz = dynamic.value(elf::DT_STRSZ).unwrap_or(0);
        for d in dynamic.entries {
            if d.is_string(endian) && d.val(endian) >= strsz {
                return Err(format!(
                    "its dynamic table names a string at offset {} of a string table of {strsz} bytes",
                    d.val(endian)
                ));
            }
        }
        Ok(())
    }

    /// The section header table inside the file, and every section's bytes within it.
    fn section_headers<'a>(elf: &Elf<'a>) -> Result<Sections<'a>, String> {
        let (header, endian, len) = (elf.header, elf.endian, elf.file_len());
        let sections = header.sections(endian, elf.data).map_err(|e| {
            format!(
                "its section header table (at byte {}, {} entries) lies outside the file of {len} bytes ({e})",
                header.e_shoff(endian),
                header.e_shnum(endian)
            )
        })?;
        for (i, s) in sections.iter().enumerate() {
            if s.sh_type(endian) == elf::SHT_NOBITS {
                continue;
            }
            let (offset, size) = (s.sh_offset(endian), s.sh_size(endian));
            if offset.checked_add(size).is_none_or(|e| e > len) {
                return Err(format!(
                    "section {i} declares file bytes {offset}..{} but the file has {len} bytes: the file is truncated or its section headers are corrupted",
                    offset.saturating_add(size)
                ));
            }
        }
        Ok(sections)
    }

    /// The dynamic symbol table's names inside its string table, its defined symbols inside a
    /// loadable segment (functions in an executable one). Returns how many dynamic symbols
    /// the section table counts (`None`: no dynamic symbol section).
    fn dynamic_symbols(
        elf: &Elf<'_>,
        sections: &Sections<'_>,
        loads: &[Load],
    ) -> Result<Option<u64>, String> {
        let endian = elf.endian;
        let symbols = sections
            .symbols(endian, elf.data, elf::SHT_DYNSYM)
            .map_err(|e| format!("its dynamic symbol table is malformed ({e})"))?;
        let names = symbols.strings();
        for (i, sym) in symbols.iter().enumerate() {
            if sym.name(endian, names).is_err() {
                return Err(format!(
                    "dynamic symbol {i}'s name (offset {}) is outside its string table",
                    sym.st_name(endian)
                ));
            }
        }
        let nsyms = (!symbols.is_empty()).then(|| symbols.len() as u64);
        for (i, sym) in symbols.iter().enumerate() {
            let shndx = sym.st_shndx(endian);
            if shndx == elf::SHN_UNDEF || shndx == elf::SHN_ABS || sym.st_type() == elf::STT_TLS {
                continue;
            }
            let v = sym.st_value(endian);
            let Some(l) = loads.iter().find(|l| l.holds_memory(v, 0)) else {
                return Err(format!(
                    "dynamic symbol {i} is defined at address {v:#x}, outside every loadable segment"
                ));
            };
            let code = matches!(sym.st_type(), elf::STT_FUNC | elf::STT_GNU_IFUNC);
            if code && l.flags & elf::PF_X.0 == 0 {
                return Err(format!(
                    "dynamic symbol {i} is a function at address {v:#x}, in a segment that is not executable"
                ));
            }
        }
        Ok(nsyms)
    }

    /// The initialiser and finaliser (`DT_INIT`, `DT_FINI`) in an executable segment.
    fn init_and_fini(dynamic: &Dynamic<'_>, loads: &[Load]) -> Result<(), String> {
        for (tag, what) in [(elf::DT_INIT, "initialiser"), (elf::DT_FINI, "finaliser")] {
            if let Some(v) = dynamic.value(tag)
                && !loads
                    .iter()
                    .any(|l| l.holds_memory(v, 1) && l.flags & elf::PF_X.0 != 0)
            {
                return Err(format!(
                    "its {what} at address {v:#x} is not in an executable segment"
                ));
            }
        }
        Ok(())
    }

    /// The code was linked against the sections' addresses: each section the program uses
    /// must be where a loadable segment maps it, in a segment with the access it needs, and
    /// the data the program writes as it runs outside the read-only-after-relocation range.
    fn placed_sections(
        elf: &Elf<'_>,
        sections: &Sections<'_>,
        segments: &Segments<'_>,
    ) -> Result<(), String> {
        let (endian, loads) = (elf.endian, &segments.loads);
        for (i, sh) in sections.iter().enumerate() {
            let flags = sh.sh_flags(endian).0;
            if flags & elf::SHF_ALLOC.0 == 0 || sh.sh_size(endian) == 0 {
                continue;
            }
            let (addr, size) = (sh.sh_addr(endian), sh.sh_size(endian));
            let nobits = sh.sh_type(endian) == elf::SHT_NOBITS;
            let placed = loads.iter().find(|l| {
                l.holds_memory(addr, size)
                    && (nobits || l.file_offset(addr) == sh.sh_offset(endian))
            });
            let name = String::from_utf8_lossy(sections.section_name(endian, sh).unwrap_or(b"?"));
            let Some(l) = placed else {
                return Err(format!(
                    "section {i} ({name}, address {addr:#x}, {size} bytes) is not where a loadable segment maps it: the program headers or section headers are corrupted"
                ));
            };
            let needs_x = flags & elf::SHF_EXECINSTR.0 != 0;
            let needs_w = flags & elf::SHF_WRITE.0 != 0;
            if (needs_x && l.flags & elf::PF_X.0 == 0) || (needs_w && l.flags & elf::PF_W.0 == 0) {
                return Err(format!(
                    "section {i} ({name}) needs a {} segment, and the one that maps it is not",
                    if needs_x { "executable" } else { "writable" }
                ));
            }
            // Made read-only after relocation (RELRO): never the data the program writes as it
            // runs (`.data`, `.bss`; linkers put `.data.rel.ro`, `.got`, the init arrays and
            // padding there, which only the loader writes).
            let run_time_data = (name.starts_with(".data") && !name.starts_with(".data.rel.ro"))
                || name.starts_with(".bss")
                || name.starts_with(".tm_clone_table");
            if let Some((lo, len)) = segments.relro
                && needs_w
                && run_time_data
                && addr < lo.saturating_add(len)
                && lo < addr.saturating_add(size)
            {
                return Err(format!(
                    "its read-only-after-relocation range (PT_GNU_RELRO) covers section {i} ({name}), which the program writes"
                ));
            }
        }
        Ok(())
    }

    /// Where the file has section headers, the dynamic table must name the very sections the
    /// linker made for its tables (a changed address or size is corruption).
    fn tables_are_their_sections(
        elf: &Elf<'_>,
        sections: &Sections<'_>,
        dynamic: &Dynamic<'_>,
    ) -> Result<(), String> {
        let endian = elf.endian;
        for (tag, section, size_tag) in LINKED_SECTIONS {
            let Some(sh) = sections
                .iter()
                .find(|sh| sections.section_name(endian, sh).ok() == Some(section.as_bytes()))
            else {
                continue;
            };
            let (addr, size) = (sh.sh_addr(endian), sh.sh_size(endian));
            let given = dynamic.value(tag);
            let given_size = size_tag.and_then(|t| dynamic.value(t));
            if given.is_some_and(|a| a != addr) || given_size.is_some_and(|n| n != size) {
                return Err(format!(
                    "its dynamic table puts {section} at {:#x} ({} bytes), where the section is at {addr:#x} ({size} bytes): the file is corrupted",
                    given.unwrap_or(0),
                    given_size.map_or_else(|| "?".to_string(), |n| n.to_string())
                ));
            }
        }
        Ok(())
    }

    /// The version tables' entry counts (`DT_VERNEEDNUM`, `DT_VERDEFNUM`) those of their
    /// sections, where the file has them.
    fn version_counts(
        elf: &Elf<'_>,
        sections: &Sections<'_>,
        dynamic: &Dynamic<'_>,
    ) -> Result<(), String> {
        let endian = elf.endian;
        for (tag, section) in [
            (elf::DT_VERNEEDNUM, ".gnu.version_r"),
            (elf::DT_VERDEFNUM, ".gnu.version_d"),
        ] {
            let sh = sections
                .iter()
                .find(|sh| sections.section_name(endian, sh).ok() == Some(section.as_bytes()));
            if let (Some(sh), Some(n)) = (sh, dynamic.value(tag))
                && n != u64::from(sh.sh_info(endian))
            {
                return Err(format!(
                    "its dynamic table counts {n} entries in {section}, which holds {}: the file is corrupted",
                    sh.sh_info(endian)
                ));
            }
        }
        Ok(())
    }

    /// The hash tables the loader looks symbols up with: every chain they lead to inside the
    /// symbol table of `nsyms` entries. Returns the symbol count, from the hash tables where
    /// the section table gives none.
    fn hash_chains(
        elf: &Elf<'_>,
        places: &Places,
        mut nsyms: Option<u64>,
    ) -> Result<Option<u64>, String> {
        let (data, endian) = (elf.data, elf.endian);
        if let Some((offset, _, end)) = places.get(elf::DT_GNU_HASH) {
            let bytes = &data[offset as usize..end as usize];
            let table = object::read::elf::GnuHashTable::<Header>::parse(endian, bytes)
                .map_err(|e| format!("its GNU hash table is malformed ({e})"))?;
            match table.symbol_table_length(endian).map(u64::from) {
                Some(n) if nsyms.is_none_or(|m| n <= m) => nsyms = nsyms.or(Some(n)),
                Some(n) => {
                    return Err(format!(
                        "its GNU hash table leads to symbol {n}, past the dynamic symbol table's {} entries",
                        nsyms.unwrap_or(0)
                    ));
                }
                // No symbol in any bucket, or a chain that does not end.
                None if table.symbol_base() == 0 || nsyms.is_none() => {}
                None => return Err("its GNU hash table has a chain without an end".into()),
            }
        }
        if let Some((offset, _, end)) = places.get(elf::DT_HASH) {
            let bytes = &data[offset as usize..end as usize];
            let table = object::read::elf::HashTable::<Header>::parse(endian, bytes)
                .map_err(|e| format!("its hash table is malformed ({e})"))?;
            let n = u64::from(table.symbol_table_length());
            if nsyms.is_some_and(|m| n > m) {
                return Err(format!(
                    "its hash table counts {n} symbols, the dynamic symbol table has {}",
                    nsyms.unwrap_or(0)
                ));
            }
            nsyms = nsyms.or(Some(n));
        }
        Ok(nsyms)
    }

    /// The relocations the loader applies: their targets inside a loadable segment it may
    /// write (any, with text relocations; else a writable one), their symbols among the
    /// `nsyms` dynamic symbols.
    fn relocations(
        elf: &Elf<'_>,
        dynamic: &Dynamic<'_>,
        places: &Places,
        loads: &[Load],
        nsyms: Option<u64>,
    ) -> Result<(), String> {
        let (data, endian) = (elf.data, elf.endian);
        let value = |tag| dynamic.value(tag);
        // Without text relocations, the loader writes only to writable segments.
        let textrel = value(elf::DT_TEXTREL).is_some()
            || value(elf::DT_FLAGS).is_some_and(|f| f & elf::DF_TEXTREL.0 != 0);
        let target_ok = |addr: u64| {
            loads
                .iter()
                .any(|l| l.holds_memory(addr, 8) && (textrel || l.flags & elf::PF_W.0 != 0))
        };
        let bad_reloc = |what: &str, i: usize, offset: u64, sym: u32| {
            if !target_ok(offset) {
                Some(format!(
                    "{what} entry {i} writes to address {offset:#x}, outside every loadable segment it may write"
                ))
            } else if nsyms.is_some_and(|n| u64::from(sym) >= n) {
                Some(format!(
                    "{what} entry {i} names symbol {sym}, past the dynamic symbol table's {} entries",
                    nsyms.unwrap_or(0)
                ))
            } else {
                None
            }
        };
        let is_rela = value(elf::DT_PLTREL).is_none_or(|v| v == elf::DT_RELA.0 as u64);
        for (tag, what, rela) in [
            (elf::DT_RELA, "relocation table (RELA)", true),
            (elf::DT_REL, "relocation table (REL)", false),
            (elf::DT_JMPREL, "PLT relocation table", is_rela),
        ] {
            let Some((offset, size, _)) = places.get(tag) else {
                continue;
            };
            let bytes = &data[offset as usize..(offset + size) as usize];
            if rela {
                let table = pod::slice_from_all_bytes::<elf::Rela64<Endianness>>(bytes)
                    .map_err(|()| format!("its {what} is not a whole number of entries"))?;
                for (i, r) in table.iter().enumerate() {
                    if let Some(m) = bad_reloc(what, i, r.r_offset(endian), r.r_sym(endian, false))
                    {
                        return Err(format!("its {m}"));
                    }
                }
            } else {
                let table = pod::slice_from_all_bytes::<elf::Rel64<Endianness>>(bytes)
                    .map_err(|()| format!("its {what} is not a whole number of entries"))?;
                for (i, r) in table.iter().enumerate() {
                    if let Some(m) = bad_reloc(what, i, r.r_offset(endian), r.r_sym(endian)) {
                        return Err(format!("its {m}"));
                    }
                }
            }
        }
        Ok(())
    }

    /// The loader applies the first `DT_RELACOUNT` entries of the RELA table as relative
    /// relocations unchecked: they must be that many, and relative.
    fn relative_count(elf: &Elf<'_>, dynamic: &Dynamic<'_>, places: &Places) -> Result<(), String> {
        let relative: Option<u32> = match std::env::consts::ARCH {
            "x86_64" => Some(8),
            "aarch64" => Some(1027),
            _ => None,
        };
        if let Some(count) = dynamic.value(elf::DT_RELACOUNT) {
            let (offset, size, _) = places.get(elf::DT_RELA).unwrap_or((0, 0, 0));
            let bytes = &elf.data[offset as usize..(offset + size) as usize];
            let table = pod::slice_from_all_bytes::<elf::Rela64<Endianness>>(bytes)
                .map_err(|()| "its relocation table (RELA) is not a whole number of entries")?;
            if count > table.len() as u64 {
                return Err(format!(
                    "its dynamic table counts {count} relative relocations of {} in all",
                    table.len()
                ));
            }
            if let Some(kind) = relative
                && let Some(i) = table[..count as usize]
                    .iter()
                    .position(|r| r.r_type(elf.endian, false).0 != kind)
            {
                return Err(format!(
                    "its relocation {i} is counted relative (DT_RELACOUNT = {count}) but is not"
                ));
            }
        }
        Ok(())
    }

    /// A segment type's name in messages.
    fn segment_kind(t: elf::ProgramType) -> String {
        match t {
            elf::PT_LOAD => "loadable".into(),
            elf::PT_DYNAMIC => "dynamic table".into(),
            elf::PT_NOTE => "notes".into(),
            elf::PT_TLS => "thread-local data".into(),
            elf::PT_GNU_EH_FRAME => "unwind table".into(),
            t => format!("type {:#x}", t.0),
        }
    }
}
