//! The viewer's OpenColorIO display transform, driven headless through `egui_kittest`: the
//! display, view and look menus change what is shown of a scene-linear preview (checked
//! against OpenColorIO's CPU transform through `lumagraph_color`), never the readout, the
//! graph or its undo history; on a display-encoded preview they are greyed out.

mod common;

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT as _, Queryable as _};
use lumagraph_color::{ColorConfig, DEFAULT_CONFIG};
use lumagraph_editor::{Editor, Pick};

use common::{editor, harness, repo};

/// The config the editor uses by default: `$OCIO`'s, else the CG config. The test's names
/// are the CG config's, so with `OCIO` set the editor is given the CG config by name.
fn config(h: &mut Harness<'static, Editor>) -> ColorConfig {
    if std::env::var_os("OCIO").is_some() {
        h.state_mut()
            .view
            .display
            .load_config(DEFAULT_CONFIG)
            .unwrap();
    }
    let spec = h.state().view.display.config_spec().to_owned();
    ColorConfig::load(&spec, std::path::Path::new(".")).unwrap()
}

/// Opens the combo box `menu` and clicks its entry `entry`.
fn choose(h: &mut Harness<'static, Editor>, menu: &str, entry: &str) {
    h.get_by_role_and_label(Role::ComboBox, menu).click();
    h.run_ok();
    h.get_by_label(entry).click();
    h.run_ok();
}

/// Where pixel (`x`, `y`) of a `width`-pixel-wide image is on screen as the viewer last
/// drew it.
fn screen(h: &Harness<'static, Editor>, width: u32, x: u32, y: u32) -> egui::Pos2 {
    let rect = h.state().view.rect.expect("drawn");
    let scale = rect.width() / width as f32;
    rect.min + egui::vec2(x as f32 + 0.5, y as f32 + 0.5) * scale
}

/// The bytes shown on screen at each of `pixels` (with the pointer away from them).
fn shown(h: &mut Harness<'static, Editor>, width: u32, pixels: &[(u32, u32)]) -> Vec<[u8; 3]> {
    h.hover_at(egui::pos2(300.0, 600.0));
    h.run_ok();
    let at: Vec<_> = pixels
        .iter()
        .map(|&(x, y)| screen(h, width, x, y))
        .collect();
    let shot = h.render().expect("a rendering");
    at.iter()
        .map(|p| {
            let px = shot.get_pixel(p.x as u32, p.y as u32).0;
            [px[0], px[1], px[2]]
        })
        .collect()
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter().zip(&b).all(|(a, b)| a.abs_diff(*b) <= 2)
}

/// What OpenColorIO's CPU transform makes of a scene-linear value, as 8 bits.
fn expected(p: &lumagraph_color::Processor, rgba: [f32; 4]) -> [u8; 3] {
    p.apply_rgb([rgba[0], rgba[1], rgba[2]])
        .map(lumagraph_render::cpu::to_u8)
}

/// `graphs/post_tonemap.ron` previewing `exposure.color` (the test chart, scene-linear):
/// the display menu starts at "(none: as the node graph shows)"; sRGB with the
/// Un-tone-mapped view shows OpenColorIO's transform of each pixel (here the sRGB encoding
/// the graph's own preview uses), ACES 2.0 SDR another picture, again OpenColorIO's, and
/// a look changes it once more. The readout keeps the scene-linear values; the graph, its
/// undo history and the preview's frames are untouched. On `tonemap.color` (display-encoded)
/// the menus are greyed out and the image is shown as it is.
#[test]
#[expect(clippy::too_many_lines, reason = "one user's sequence of steps")]
fn display_and_view_menus_change_what_is_shown_only() {
    let Some(ed) = editor(Some(&repo("graphs/post_tonemap.ron")), None) else {
        return;
    };
    let mut h = harness(ed);
    let config = config(&mut h);
    h.state_mut().select(vec!["exposure".into()]);
    h.run_ok();
    assert_eq!(
        h.state().effective_port().as_deref(),
        Some("exposure.color")
    );
    let (image, _) = h.state().preview.linear.clone().expect("an image");
    // Fitted, the image is as wide as the side panel.
    let fitted = h.state().view.rect.expect("drawn").width();
    // Zoomed in (nearest-neighbour pixels) about the boundary between the saturated hue
    // sweep at luminance about 1 (rows 128–191) and the grey patches (row 192 on; the
    // middle one is 0.18).
    let view = &mut h.state_mut().view;
    view.zoom = Some(4.0);
    view.center = egui::vec2(256.0, 192.0);
    h.run_ok();
    let pixels = [(250, 180), (262, 186), (256, 200)];
    let linear: Vec<[f32; 4]> = pixels
        .iter()
        .map(|&(x, y)| image.pixels[(y * image.width + x) as usize])
        .collect();
    let graph = h.state().doc.graph.clone();
    let (frames, rebuilds) = {
        let s = &h.state().preview.stats;
        (s.frames, s.rebuilds)
    };
    let none = lumagraph_editor::display::NONE;
    let as_graph = shown(&mut h, image.width, &pixels);
    let graph_bytes: Vec<[u8; 3]> = linear
        .iter()
        .map(|v| {
            let one = lumagraph_render::cpu::Image {
                width: 1,
                height: 1,
                pixels: vec![*v],
            };
            let b = lumagraph_render::image_io::to_rgba8(&one, true);
            [b[0], b[1], b[2]]
        })
        .collect();
    for (s, g) in as_graph.iter().zip(&graph_bytes) {
        assert!(
            close(*s, *g),
            "off: shown {s:?}, the graph's encoding {g:?}"
        );
    }
    assert!(h.state().view.display.display.is_none(), "off by default");

    // sRGB, Un-tone-mapped.
    choose(&mut h, "display", "sRGB - Display");
    assert_eq!(
        h.state().view.display.view,
        "ACES 2.0 - SDR 100 nits (Rec.709)",
        "the display's default view"
    );
    choose(&mut h, "view", "Un-tone-mapped");
    let untonemapped = config
        .display_processor("", "sRGB - Display", "Un-tone-mapped", "")
        .unwrap();
    let got = shown(&mut h, image.width, &pixels);
    for (i, v) in linear.iter().enumerate() {
        let want = expected(&untonemapped, *v);
        assert!(
            close(got[i], want),
            "Un-tone-mapped {v:?}: {:?} vs {want:?}",
            got[i]
        );
        // For values in [0, 1], that is the sRGB encoding of the graph's own preview.
        assert!(
            close(want, graph_bytes[i]),
            "{want:?} vs {:?}",
            graph_bytes[i]
        );
    }
    // The readout: the scene-linear value.
    let (x, y) = pixels[2];
    h.hover_at(screen(&h, image.width, x, y));
    h.run_ok();
    let r = h.state().view.hover.expect("a readout");
    assert_eq!((r.x, r.y), (x, y));
    assert_eq!(r.rgba, linear[2]);

    // ACES 2.0 SDR: another picture, OpenColorIO's.
    choose(&mut h, "view", "ACES 2.0 - SDR 100 nits (Rec.709)");
    let aces = config
        .display_processor(
            "",
            "sRGB - Display",
            "ACES 2.0 - SDR 100 nits (Rec.709)",
            "",
        )
        .unwrap();
    let got = shown(&mut h, image.width, &pixels);
    for (i, v) in linear.iter().enumerate() {
        let want = expected(&aces, *v);
        assert!(
            close(got[i], want),
            "ACES 2.0 {v:?}: {:?} vs {want:?}",
            got[i]
        );
        assert!(
            !close(want, expected(&untonemapped, *v)),
            "pick pixels the views differ at: {v:?}"
        );
    }
    let (ms, w, hgt) = h.state().view.display.last_cost.expect("timed");
    eprintln!("display transform of a {w}×{hgt} preview on the CPU: {ms:.1} ms");
    h.hover_at(screen(&h, image.width, x, y));
    h.run_ok();
    assert_eq!(h.state().view.hover.expect("a readout").rgba, linear[2]);

    // A look, before the view.
    // The menus wrap within the side panel: it is as wide as before.
    h.state_mut().view.zoom = None;
    h.run_ok();
    assert_eq!(h.state().view.rect.expect("drawn").width(), fitted);
    let view = &mut h.state_mut().view;
    view.zoom = Some(4.0);
    view.center = egui::vec2(256.0, 192.0);
    h.run_ok();

    let look = config
        .looks()
        .first()
        .cloned()
        .expect("the CG config has a look");
    choose(&mut h, "look", &look);
    assert_eq!(h.state().view.display.look.as_deref(), Some(look.as_str()));
    let with_look = config
        .display_processor(
            "",
            "sRGB - Display",
            "ACES 2.0 - SDR 100 nits (Rec.709)",
            &look,
        )
        .unwrap();
    let got = shown(&mut h, image.width, &pixels);
    for (i, v) in linear.iter().enumerate() {
        let want = expected(&with_look, *v);
        assert!(
            close(got[i], want),
            "with {look} {v:?}: {:?} vs {want:?}",
            got[i]
        );
    }

    // Nothing of it reached the graph, its undo history or the preview.
    let ed = h.state();
    assert_eq!(ed.doc.graph, graph);
    assert!(!ed.doc.is_dirty());
    assert!(!ed.title().starts_with('●'), "{}", ed.title());
    assert_eq!(ed.doc.can_undo_redo(), (false, false));
    assert_eq!(
        (ed.preview.stats.frames, ed.preview.stats.rebuilds),
        (frames, rebuilds)
    );

    // Display-encoded (after the Tonemap): greyed out, shown as it is.
    h.state_mut().select(vec!["tonemap".into()]);
    h.run_ok();
    assert_eq!(h.state().effective_port().as_deref(), Some("tonemap.color"));
    for menu in ["display", "view", "look"] {
        let node = h.get_by_role_and_label(Role::ComboBox, menu);
        assert!(
            node.accesskit_node().is_disabled(),
            "{menu} is not greyed out"
        );
    }
    let ldr = h.state().preview.image.clone().expect("an image");
    let got = shown(&mut h, image.width, &pixels);
    for (i, &(x, y)) in pixels.iter().enumerate() {
        let k = 4 * (y * ldr.width + x) as usize;
        let want = [ldr.rgba[k], ldr.rgba[k + 1], ldr.rgba[k + 2]];
        assert!(close(got[i], want), "LDR as is: {:?} vs {want:?}", got[i]);
    }
    // Back to scene-linear, back to "(none…)": the graph's encoding again.
    h.state_mut().select(vec!["exposure".into()]);
    h.run_ok();
    assert!(
        !h.get_by_role_and_label(Role::ComboBox, "display")
            .accesskit_node()
            .is_disabled()
    );
    choose(&mut h, "display", none);
    assert!(h.state().view.display.display.is_none());
    assert_eq!(shown(&mut h, image.width, &pixels), as_graph);
}

/// "load config.ocio…" (in the display menu) opens the file dialog for a `config.ocio`; a picked config replaces the
/// display and view the new one lacks with its defaults and shows its transform; one that
/// cannot be loaded is said in the status line and the current one stays.
#[test]
fn another_config_is_picked_for_the_viewer() {
    let Some(ed) = editor(Some(&repo("graphs/post_tonemap.ron")), None) else {
        return;
    };
    let mut h = harness(ed);
    let _ = config(&mut h);
    h.state_mut().select(vec!["exposure".into()]);
    h.run_ok();
    choose(&mut h, "display", "sRGB - Display");
    choose(&mut h, "display", lumagraph_editor::display::LOAD_CONFIG);
    let pick = h.state().file_dialog.as_ref().map(|(p, _)| p.clone());
    assert_eq!(pick, Some(Pick::OcioConfig));
    h.state_mut().file_dialog = None;

    let user = repo("tests/color/user_config/config.ocio");
    let ed = h.state_mut();
    ed.apply_pick(&Pick::OcioConfig, &user);
    assert_eq!(
        ed.message.as_ref().map(|m| m.1),
        Some(false),
        "{:?}",
        ed.message
    );
    let d = &mut ed.view.display;
    assert_eq!(d.config_spec(), user.display().to_string());
    assert_eq!(
        (d.display.as_deref(), d.view.as_str()),
        (Some("sRGB Display"), "Film")
    );
    let user_config =
        ColorConfig::load(&user.display().to_string(), std::path::Path::new(".")).unwrap();
    let want = user_config
        .display_processor("", "sRGB Display", "Film", "")
        .unwrap()
        .apply_rgb([0.18, 0.18, 0.18]);
    let got = d
        .processor()
        .expect("a processor")
        .apply_rgb([0.18, 0.18, 0.18]);
    assert_eq!(got, want);
    h.run_ok();
    h.get_by_role_and_label(Role::ComboBox, "display").click();
    h.run_ok();
    h.get_by_label(lumagraph_editor::display::DEFAULT_CONFIG_ENTRY);
    h.key_press(egui::Key::Escape);
    h.run_ok();

    let ed = h.state_mut();
    ed.apply_pick(&Pick::OcioConfig, &repo("graphs/post_tonemap.ron"));
    let (text, error) = ed.message.clone().expect("a message");
    assert!(error, "{text}");
    assert!(text.contains("post_tonemap.ron"), "{text}");
    assert_eq!(ed.view.display.config_spec(), user.display().to_string());
    assert!(!ed.doc.is_dirty());
}

/// Making the graph ACEScg (what Edit ▸ Working space does; one undo step, saved with
/// the graph): the preview is then in ACEScg, and the viewer converts it to Rec. 709 before its
/// sRGB encoding, so what is shown does not change (within 2 codes at three pixels).
#[test]
fn the_working_space_menu_changes_the_graph_not_what_is_shown() {
    let Some(ed) = editor(Some(&repo("graphs/post_tonemap.ron")), None) else {
        return;
    };
    let mut h = harness(ed);
    h.state_mut().select(vec!["exposure".into()]);
    h.run_ok();
    let (image, _) = h.state().preview.linear.clone().expect("an image");
    let view = &mut h.state_mut().view;
    view.zoom = Some(4.0);
    view.center = egui::vec2(256.0, 192.0);
    h.run_ok();
    let pixels = [(250, 180), (262, 186), (256, 200)];
    let before = shown(&mut h, image.width, &pixels);
    h.state_mut()
        .doc
        .set_working_space(lumagraph_graph::WorkingSpace::AcesCg);
    for _ in 0..4 {
        h.run_ok();
    }
    assert_eq!(
        h.state().doc.graph.working_space,
        lumagraph_graph::WorkingSpace::AcesCg
    );
    let (aces, _) = h.state().preview.linear.clone().expect("an image");
    assert_ne!(aces.pixels, image.pixels, "the preview is in ACEScg");
    let after = shown(&mut h, image.width, &pixels);
    for (a, b) in before.iter().zip(&after) {
        assert!(close(*a, *b), "{before:?} shown, {after:?} in ACEScg");
    }
    assert!(h.state_mut().doc.undo());
    assert_eq!(
        h.state().doc.graph.working_space,
        lumagraph_graph::WorkingSpace::Rec709
    );
}
