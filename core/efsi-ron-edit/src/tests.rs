use super::path::{Seg, parse_path};
use super::tree::{Atom, Kind, parse_ron};
use super::*;

const ALIASES: Aliases = &[("nr", "nx"), ("r", "x")];

#[test]
fn paths_parse_with_indices_and_aliases() {
    assert_eq!(
        parse_path("output.probes[2].at", ALIASES).unwrap(),
        vec![
            Seg::Key("output".into()),
            Seg::Key("probes".into()),
            Seg::Index(2),
            Seg::Key("at".into())
        ]
    );
    assert_eq!(
        parse_path("grid.nr", ALIASES).unwrap(),
        vec![Seg::Key("grid".into()), Seg::Key("nx".into())]
    );
    assert_eq!(parse_path("gravity.1", ALIASES).unwrap()[1], Seg::Index(1));
    for bad in ["", "a..b", "a[x]", "a[1", "a[1]b", ".a"] {
        assert!(parse_path(bad, ALIASES).is_err(), "{bad}");
    }
}

#[test]
fn the_tree_keeps_spans_through_comments_and_strings() {
    let text = "#![enable(implicit_some)]\n// c\nS(a: (1, 2.5e-3), /* (x: */ b: \"q)\", c: {\"G\": 1e6,}, d: Some([A, B(x: 1)]), e: r#\"a\"#)";
    let (root, _) = (parse_ron(text).unwrap(), ());
    let Kind::Struct(f) = &root.kind else {
        panic!("{root:?}")
    };
    let names: Vec<_> = f.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(names, ["a", "b", "c", "d", "e"]);
    assert_eq!(&text[f[1].1.start..f[1].1.end], "\"q)\"");
    assert!(f[2].1.trailing_comma);
    let Kind::Tuple(_, items) = &f[0].1.kind else {
        panic!()
    };
    assert_eq!(items[1].atom(), Some(Atom::Float));
    assert_eq!(items[0].atom(), Some(Atom::Int));
}

/// Set replaces a value in place, inserts an absent one with its containers (their kind
/// and the value's type from the hints), and get reads values back.
#[test]
fn set_and_get_edit_the_text_in_place() {
    let doc = Document::parse("S(a: 1, m: {\"k\": 2.0}, o: None) // end", ALIASES).unwrap();
    let hints =
        Document::parse("S(a: 1, m: {}, o: Some(0.5), s: (t: (u: Blue)))", ALIASES).unwrap();
    let set = |p: &str, v: Value| doc.set(Some(&hints), &Path::parse(p, ALIASES).unwrap(), &v);
    assert_eq!(
        set("a", Value::Float(3.0)).unwrap(),
        "S(a: 3, m: {\"k\": 2.0}, o: None) // end"
    );
    assert!(set("a", Value::Float(3.5)).unwrap_err().contains("integer"));
    // A real written as a whole number in the text is real by the hints.
    let real = Document::parse("S(a: 1, r: 1)", ALIASES).unwrap();
    let real_hints = Document::parse("S(a: 1, r: 1.0)", ALIASES).unwrap();
    assert_eq!(
        real.set(
            Some(&real_hints),
            &Path::parse("r", ALIASES).unwrap(),
            &Value::Ron("0.3".into())
        )
        .unwrap(),
        "S(a: 1, r: 0.3)"
    );
    assert_eq!(
        set("m.q", Value::Int(4)).unwrap(),
        "S(a: 1, m: {\"k\": 2.0, \"q\": 4}, o: None) // end"
    );
    assert_eq!(
        set("o", Value::Int(4)).unwrap(),
        "S(a: 1, m: {\"k\": 2.0}, o: 4) // end"
    );
    assert_eq!(
        set("s.t.u", Value::Str("Red".into())).unwrap(),
        "S(a: 1, m: {\"k\": 2.0}, o: None, s: (t: (u: Red))) // end"
    );
    assert!(set("a.b", Value::Int(1)).unwrap_err().contains("integer"));
    let get = |p: &str| doc.get(&Path::parse(p, ALIASES).unwrap());
    assert_eq!(get("a").unwrap(), Some(Value::Int(1)));
    assert_eq!(get("m.k").unwrap(), Some(Value::Float(2.0)));
    assert_eq!(get("o").unwrap(), Some(Value::Ron("None".into())));
    assert_eq!(get("zz").unwrap(), None);
    assert!(get("a.b").unwrap_err().contains("integer"));
    assert!(
        doc.check_reachable(&Path::parse("a.b", ALIASES).unwrap())
            .is_err()
    );
    assert!(
        doc.check_reachable(&Path::parse("o.x", ALIASES).unwrap())
            .is_ok()
    );
}

#[test]
fn paths_overlap_when_one_holds_the_other() {
    let p = |s: &str| Path::parse(s, ALIASES).unwrap();
    assert!(p("grid").overlaps(&p("grid.nx")));
    assert!(p("grid.nr").overlaps(&p("grid.nx")));
    assert!(!p("grid.nx").overlaps(&p("grid.ny")));
    assert!(!Path::default().overlaps(&p("grid")));
    assert_eq!(p("output.probes[2].at").to_string(), "output.probes[2].at");
}

/// Text nested deeper than [`MAX_DEPTH`] is refused with a message, whatever its depth (the
/// parser must not run off its stack), and text at the limit is read.
#[test]
fn nesting_is_capped_at_the_scene_readers_limit() {
    let nested = |n: usize| format!("{}1{}", "(".repeat(n), ")".repeat(n));
    assert!(parse_ron(&nested(MAX_DEPTH)).is_ok());
    for n in [MAX_DEPTH + 1, 10_000, 1_000_000] {
        let (at, m) = parse_ron(&nested(n)).unwrap_err();
        assert_eq!(at, MAX_DEPTH + 1, "{n}");
        assert_eq!(
            m,
            "nested deeper than 128 levels, the most a scene may nest"
        );
    }
    let lists = format!("{}{}", "[".repeat(10_000), "]".repeat(10_000));
    assert!(parse_ron(&lists).unwrap_err().1.contains("nested deeper"));
    let maps = "{1:".repeat(10_000);
    assert!(parse_ron(&maps).unwrap_err().1.contains("nested deeper"));
    // A value to set is read by the same parser; the message quotes it cut short.
    let doc = Document::parse("S(a: (1, 2))", ALIASES).unwrap();
    let e = doc
        .set(
            None,
            &Path::parse("a", ALIASES).unwrap(),
            &Value::Ron(nested(10_000)),
        )
        .unwrap_err();
    assert!(e.contains("nested deeper than 128 levels"), "{e}");
    assert!(e.contains("… (20001 characters)"), "{e}");
    assert!(e.len() < 300, "{}", e.len());
    let o = overrides::Override::set("a", Value::Ron(nested(10_000)));
    assert_eq!(
        o.brief().chars().count(),
        60 + "… (20007 characters)".chars().count()
    );
    assert_eq!(o.to_string().len(), 20_007);
}
