use super::Resources;

/// The first maker of a type's value runs, later ones do not; a failed maker keeps
/// nothing, so the next stage to ask makes it again (and reports its own error).
#[test]
fn resources_make_each_value_once_and_keep_no_failure() {
    let mut r = Resources::default();
    let mut calls = 0;
    let e = r
        .get_or_try_insert_with::<u32, String>(|| {
            calls += 1;
            Err("no law".into())
        })
        .unwrap_err();
    assert_eq!(e, "no law");
    assert!(r.get::<u32>().is_none());
    for want in [7, 7] {
        let got = *r
            .get_or_try_insert_with::<u32, String>(|| {
                calls += 1;
                Ok(7)
            })
            .unwrap();
        assert_eq!(got, want);
    }
    assert_eq!(calls, 2, "made once after the failure, then taken");
    // One value per type: another type is made separately.
    assert_eq!(
        r.get_or_try_insert_with::<&str, ()>(|| Ok("law")),
        Ok(&"law")
    );
    assert_eq!(r.get::<u32>(), Some(&7));
}
