//! The app driven without a real terminal: ratatui's test backend, with the
//! worker thread waited on with a timeout.

use std::time::Duration;

use ratatui::backend::TestBackend;
use ratatui::style::Color;
use ratatui::Terminal;

use super::app::App;
use super::color::ColorMode;
use super::graphics::symbols::{self, Symbols};
use super::keys::Key;
use crate::render::{post, Feature, Features, PlanPolicy, Progressive, SceneRequest, Session};

const WAIT: Duration = Duration::from_secs(30);

fn app(spec: &str, off: &[Feature]) -> App {
    let req = SceneRequest {
        size: Some((24, 16)),
        features: Features::all().without(off),
        ..SceneRequest::new(spec)
    };
    let (session, warnings) = Session::open(&req).unwrap();
    let mut app = App::new(session, warnings, ColorMode::Truecolor, None).unwrap();
    app.jobs.export_size = req.size;
    app
}

fn terminal(w: u16, h: u16) -> Terminal<TestBackend> {
    Terminal::new(TestBackend::new(w, h)).unwrap()
}

/// Lays the app out for the terminal, waits for a full pass of that view,
/// and draws.
fn settle(t: &mut Terminal<TestBackend>, app: &mut App) -> String {
    let size = t.size().unwrap();
    app.update(ratatui::layout::Rect::new(0, 0, size.width, size.height));
    assert!(app.wait_frame(WAIT).unwrap(), "no pass within {WAIT:?}");
    super::draw(t, app).unwrap();
    text(t)
}

fn text(t: &Terminal<TestBackend>) -> String {
    let b = t.backend().buffer();
    (0..b.area.height)
        .map(|y| {
            (0..b.area.width)
                .map(|x| b[(x, y)].symbol())
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn line_with<'a>(screen: &'a str, needle: &str) -> &'a str {
    screen
        .lines()
        .find(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("no line with {needle:?} in\n{screen}"))
}

#[test]
fn a_frame_shows_every_panel() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    let s = settle(&mut t, &mut app);
    for title in [
        "BVH: sah, 32 triangles",
        "Features",
        "Render",
        "Ray tree",
        "cornell",
    ] {
        assert!(s.contains(title), "{title:?} missing in\n{s}");
    }
    assert!(s.contains("spp") && s.contains("rays/s"), "{s}");
    assert!(s.contains("wide nodes"), "{s}");
    // The viewport is half blocks: each cell shows its two pixels.
    let b = t.backend().buffer();
    let v = app.display.layout.image;
    let frame = app.link.current_frame().unwrap();
    for (cx, cy) in [
        (v.width / 2, v.height / 2),
        (1, 1),
        (v.width - 1, v.height - 1),
    ] {
        let cell = &b[(v.x + cx, v.y + cy)];
        assert!(["▀", "▄", " "].contains(&cell.symbol()), "{cell:?}");
        let shown = symbols::shown_cell(Symbols::Half, cell.symbol(), cell.fg, cell.bg).unwrap();
        let px = |y: u32| {
            crate::color::srgb(frame.image[(y * frame.width + cx as u32) as usize]).map(f32::from)
        };
        assert_eq!(
            shown,
            vec![px(2 * cy as u32), px(2 * cy as u32 + 1)],
            "{cell:?}"
        );
    }
    assert_eq!(
        app.display.view_size(),
        (v.width as u32, 2 * v.height as u32)
    );
}

/// At 80x24, with every feature listed, the Render panel still shows the
/// samples and the error: the BVH panel gives up lines first.
#[test]
fn the_smallest_terminal_shows_samples_and_error() {
    let mut app = app("cornell-area", &[]);
    let mut t = terminal(80, 24);
    settle(&mut t, &mut app);
    let end = std::time::Instant::now() + WAIT;
    while app.current_frame().is_none_or(|f| f.spp < 2) && std::time::Instant::now() < end {
        app.poll().unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    let s = settle(&mut t, &mut app);
    let render = &s[s.find("Render").expect("a Render panel")..];
    assert!(render.contains("spp") && render.contains("error"), "{s}");
}

#[test]
fn toggling_a_feature_changes_the_features_panel() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    let s = settle(&mut t, &mut app);
    assert!(line_with(&s, "shadows").contains("shadows        on"));
    let before = app.generation();
    app.handle_key(Key::Char('1'));
    assert!(
        app.generation() > before,
        "toggling shadows restarts rendering"
    );
    let s = settle(&mut t, &mut app);
    assert!(
        line_with(&s, "shadows").contains("shadows        off"),
        "{s}"
    );
    // Cornell has no textures: the panel says so, and toggling says so.
    assert!(line_with(&s, "4 textures").contains("no textures"), "{s}");
    let before = app.generation();
    app.handle_key(Key::Char('4'));
    assert_eq!(
        app.generation(),
        before,
        "a feature the scene does not need changes nothing"
    );
    assert!(
        app.status
            .message()
            .contains("not needed: no textures in scene"),
        "{}",
        app.status.message()
    );
}

#[test]
fn selecting_a_pixel_fills_the_debug_pane() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    let s = settle(&mut t, &mut app);
    assert!(!s.contains("camera ray"));
    app.handle_key(Key::Char('v'));
    let s = settle(&mut t, &mut app);
    assert!(s.contains("camera ray"), "{s}");
    let (w, h) = app.display.view_size();
    assert!(s.contains(&format!("pixel ({}, {})", w / 2, h / 2)), "{s}");
    // In select mode the arrows move the cursor, not the camera.
    let g = app.generation();
    app.handle_key(Key::Right);
    app.handle_key(Key::Char('j'));
    assert_eq!(app.generation(), g);
    let s = settle(&mut t, &mut app);
    assert!(
        s.contains(&format!("pixel ({}, {})", w / 2 + 1, h / 2 + 1)),
        "{s}"
    );
}

#[test]
fn folds_open_and_close() {
    // The area light's 16 samples fold into one line.
    let mut app = app("cornell-area", &[]);
    let mut t = terminal(120, 40);
    settle(&mut t, &mut app);
    let (w, h) = app.display.view_size();
    app.select(w / 2, h * 7 / 8, 0);
    let lines = app.inspector.lines().to_vec();
    let folded = lines.len();
    assert!(lines.iter().any(|l| l.text.starts_with("[+] 16 samples")));
    // Enter opens the first fold below the cursor and scrolls to it.
    app.handle_key(Key::Enter);
    let s = settle(&mut t, &mut app);
    assert!(s.contains("[-] 16 samples"), "{s}");
    assert_eq!(app.inspector.lines().len(), folded + 16);
    app.handle_key(Key::Char(' '));
    assert_eq!(app.inspector.lines().len(), folded);
}

#[test]
fn rays_are_drawn_into_the_view() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    let (w, h) = app.display.view_size();
    // A pixel whose shadow ray was traced (lit by the light or blocked).
    let has_shadow_ray = |app: &mut App| {
        let tree = app.inspector.tree().unwrap();
        tree.root
            .lights
            .iter()
            .flat_map(|l| &l.samples)
            .any(|s| s.shadow_ray.is_some())
    };
    let found = (0..h).rev().step_by(3).any(|y| {
        app.select(w / 3, y, 0);
        has_shadow_ray(&mut app)
    });
    assert!(found, "no pixel with a shadow ray");
    let count = |t: &Terminal<TestBackend>| {
        let b = t.backend().buffer();
        let ray = [Color::Rgb(255, 255, 255), Color::Rgb(255, 0, 0)];
        b.content()
            .iter()
            .filter(|c| ray.contains(&c.fg) || ray.contains(&c.bg))
            .count()
    };
    settle(&mut t, &mut app);
    let before = count(&t);
    app.handle_key(Key::Char('o'));
    settle_pixel(&mut t, &mut app);
    assert!(count(&t) > before + 3, "{before} -> {}", count(&t));
}

#[test]
fn pixel_overlays_cycle_and_show_the_ray_at_the_debug_cursor() {
    use crate::viz::{View, PIXEL_VIEWS as VIEWS};
    let mut app = app("cornell", &[]);
    let mut t = terminal(220, 40);
    settle(&mut t, &mut app);
    let (w, h) = app.display.view_size();
    // A pixel with a shadow ray: ray 1 of its tree.
    let found = (0..h).rev().step_by(2).any(|y| {
        app.select(w / 3, y, 0);
        app.inspector.lines().iter().any(|l| l.ray == Some(1))
    });
    assert!(found, "no pixel with a shadow ray");
    for v in &VIEWS[..4] {
        app.handle_key(Key::Char('o'));
        assert_eq!(app.overlays.pixel, Some(*v));
    }
    assert_eq!(app.overlays.pixel, Some(View::Traversal));
    // Above the first ray line the camera ray's walk is shown.
    assert_eq!(app.inspector.cursor_ray(), None);
    let s = settle_pixel(&mut t, &mut app);
    assert!(s.contains("ray 0: camera ray"), "{s}");
    while app.inspector.cursor_ray() != Some(1) {
        let before = app.inspector.cursor;
        app.handle_key(Key::Char(']'));
        assert!(app.inspector.cursor > before, "no line of ray 1");
    }
    assert_eq!(app.pixel_request().unwrap().ray, Some(1));
    let s = settle_pixel(&mut t, &mut app);
    assert!(s.contains("ray 1: shadow ray"), "{s}");
    assert_eq!(app.link.current_pixel().unwrap().request.ray, Some(1));
    // The whole-tree views take no ray; after the last view, off.
    for _ in 4..VIEWS.len() {
        app.handle_key(Key::Char('o'));
    }
    assert_eq!(app.overlays.pixel, Some(View::Samples));
    assert_eq!(app.pixel_request().unwrap().ray, None);
    app.handle_key(Key::Char('o'));
    assert_eq!(app.overlays.pixel, None);
    assert_eq!(app.pixel_request(), None);
}

/// Waits for the worker to send a pass with the app's film view drawn in,
/// draws, and gives the screen's text.
fn settle_film_view(t: &mut Terminal<TestBackend>, app: &mut App) -> String {
    let end = std::time::Instant::now() + WAIT;
    let want = app
        .overlays
        .image
        .filter(|v| v.source() == crate::viz::DrawnFrom::Film);
    while app
        .link
        .current_frame()
        .is_none_or(|f| f.film_view.as_ref().map(|v| v.0) != want)
    {
        assert!(
            std::time::Instant::now() < end,
            "no film view within {WAIT:?}"
        );
        app.poll().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    super::draw(t, app).unwrap();
    text(t)
}

#[test]
fn bloom_samples_and_error_are_the_last_view_overlays() {
    use crate::viz::View;
    let mut app = app("cornell", &[]);
    let mut t = terminal(240, 40);
    settle(&mut t, &mut app);
    for _ in 0..5 {
        app.handle_key(Key::Char('g'));
    }
    assert_eq!(app.overlays.image, Some(View::Bloom));
    // The worker draws each into the next pass it sends.
    let s = settle_film_view(&mut t, &mut app);
    assert!(s.contains("over the threshold (luminance > 1)"), "{s}");
    assert!(s.contains("kernel 25x25"), "{s}");
    app.handle_key(Key::Char('g'));
    assert_eq!(app.overlays.image, Some(View::Spp));
    let s = settle_film_view(&mut t, &mut app);
    assert!(s.contains("samples per pixel"), "{s}");
    app.handle_key(Key::Char('g'));
    assert_eq!(app.overlays.image, Some(View::Error));
    let s = settle_film_view(&mut t, &mut app);
    assert!(s.contains("estimated relative error per pixel"), "{s}");
    app.handle_key(Key::Char('g'));
    assert_eq!(app.overlays.image, None);
}

/// Settles, then waits for the worker's pixel overlay and draws again.
fn settle_pixel(t: &mut Terminal<TestBackend>, app: &mut App) -> String {
    settle(t, app);
    let end = std::time::Instant::now() + WAIT;
    while app.link.current_pixel().is_none() {
        assert!(
            std::time::Instant::now() < end,
            "no pixel overlay within {WAIT:?}"
        );
        app.poll().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    super::draw(t, app).unwrap();
    text(t)
}

#[test]
fn a_small_terminal_shows_a_message() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(60, 20);
    super::draw(&mut t, &mut app).unwrap();
    assert!(
        text(&t).contains("terminal too small (need 80x24"),
        "{}",
        text(&t)
    );
    let mut t = terminal(80, 24);
    let s = settle(&mut t, &mut app);
    assert!(s.contains("Features") && s.contains("Ray tree"), "{s}");
}

#[test]
fn help_lists_every_binding() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(150, 64);
    settle(&mut t, &mut app);
    app.handle_key(Key::Char('?'));
    super::draw(&mut t, &mut app).unwrap();
    let s = text(&t);
    for r in super::keys::ROWS {
        assert!(s.contains(r.help), "{:?} missing from the help", r.help);
    }
    // Keys go to the popup while it is open; q closes it, not the app.
    let g = app.generation();
    app.handle_key(Key::Char('w'));
    assert_eq!(app.generation(), g);
    app.handle_key(Key::Char('q'));
    assert!(app.popup.is_none() && !app.quit);
}

#[test]
fn deterministic_scenes_say_exact() {
    let mut app = app("cornell", &[Feature::Supersampling]);
    let mut t = terminal(100, 30);
    let s = settle(&mut t, &mut app);
    assert!(s.contains("exact"), "{s}");
    assert!(app.current_frame().unwrap().done);
}

#[test]
fn the_builder_switch_rebuilds() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    app.handle_key(Key::Char('b'));
    let s = settle(&mut t, &mut app);
    assert!(s.contains("BVH: median"), "{s}");
    assert!(
        app.status
            .message()
            .contains("rebuilt with the median builder"),
        "{}",
        app.status.message()
    );
}

#[test]
fn worst_pixel_keys_select_a_pixel() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    app.handle_key(Key::Char('B'));
    assert!(app.inspector.selected.is_some(), "{}", app.status.message());
    app.handle_key(Key::Char('n'));
    assert!(
        app.status.message().contains("no pixel had a NaN"),
        "{}",
        app.status.message()
    );
}

#[test]
fn export_writes_a_png_in_the_background() {
    let dir = std::env::temp_dir().join(format!("rayterm-tui-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut app = app("cornell", &[]);
    app.jobs.export_dir = dir.clone();
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    app.handle_key(Key::Char('p'));
    let end = std::time::Instant::now() + WAIT;
    while app.jobs.export_progress().is_some() && std::time::Instant::now() < end {
        std::thread::sleep(Duration::from_millis(10));
        app.poll().unwrap();
    }
    assert!(
        app.status.message().starts_with("saved "),
        "{}",
        app.status.message()
    );
    let path = dir.join("rayterm-cornell-001.png");
    let img = image::open(&path).unwrap();
    assert_eq!((img.width(), img.height()), (24, 16));
    assert!(app.status.message().contains(&path.display().to_string()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_click_selects_the_pixel_under_it() {
    use ratatui::crossterm::event::{Event, KeyModifiers, MouseButton, MouseEvent, MouseEventKind};
    let mut app = app("cornell", &[]);
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    let v = app.display.layout.image;
    let click = |column, row| {
        Event::Mouse(MouseEvent {
            kind: MouseEventKind::Down(MouseButton::Left),
            column,
            row,
            modifiers: KeyModifiers::NONE,
        })
    };
    app.handle_event(&click(v.x + 5, v.y + 3));
    let s = app.inspector.selected.unwrap();
    assert_eq!((s.x, s.y), (5, 6), "cell row 3 holds pixel rows 6 and 7");
    // Clicks outside the viewport select nothing new.
    app.handle_event(&click(v.x + v.width + 2, v.y));
    assert_eq!(app.inspector.selected.map(|s| (s.x, s.y)), Some((5, 6)));
}

#[test]
fn no_plan_runs_every_enabled_stage_in_the_view_and_its_export() {
    let req = SceneRequest {
        size: Some((24, 16)),
        policy: PlanPolicy::Everything,
        ..SceneRequest::new("cornell")
    };
    let (session, warnings) = Session::open(&req).unwrap();
    let mut app = App::new(session, warnings, ColorMode::Truecolor, None).unwrap();
    app.jobs.export_size = req.size;
    let mut t = terminal(100, 30);
    let s = settle(&mut t, &mut app);
    // Cornell has no textures, glossy materials or environment map, yet
    // with --no-plan their stages run, and the panel says so.
    assert!(
        app.choice.plan().textures && app.choice.plan().glossy && app.choice.plan().environment
    );
    assert!(
        line_with(&s, "textures").contains("textures       on"),
        "{s}"
    );
    app.handle_key(Key::Char('1'));
    assert!(
        app.choice.plan().textures && !app.choice.plan().shadows,
        "toggles keep the policy"
    );
    let dir = std::env::temp_dir().join(format!("rayterm-tui-noplan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    app.jobs.export_dir = dir.clone();
    app.handle_key(Key::Char('p'));
    let end = std::time::Instant::now() + WAIT;
    while app.jobs.export_progress().is_some() && std::time::Instant::now() < end {
        std::thread::sleep(Duration::from_millis(10));
        app.poll().unwrap();
    }
    assert!(
        app.status.message().starts_with("saved "),
        "{}",
        app.status.message()
    );
    // The export rendered the view's plan: every stage but the shadows.
    let req = SceneRequest {
        features: Features::all().without(&[Feature::Shadows]),
        ..req
    };
    let (s, _) = Session::open(&req).unwrap();
    let film = Progressive::render(&s.tracer(), s.scene.settings.spp);
    let shown = post::display(film.image(), 24, 16, &s.plan, &s.scene.settings.bloom);
    let want = post::to_rgb8(&shown.image, 24, 16);
    let got = image::open(dir.join("rayterm-cornell-001.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(got, want);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_pixel_before_and_after_bloom_is_the_films_as_inspect_gives_it() {
    let mut app = app("cornell-area", &[]);
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    let (w, h) = app.display.view_size();
    app.select(w / 2, h / 3, 0);
    let tree = app.inspector.tree().unwrap().clone();
    let spp = tree
        .pixel_spp
        .expect("bloom runs, so the pixel's values are known");
    // What `rayterm inspect --size WxH --spp N` computes: the image at N
    // spp, before and after bloom.
    let req = SceneRequest {
        size: Some((w, h)),
        ..SceneRequest::new("cornell-area")
    };
    let (s, _) = Session::open(&req).unwrap();
    let film = Progressive::render(&s.tracer(), spp);
    let shown = post::display(film.image(), w, h, &s.plan, &s.scene.settings.bloom);
    let mut want = crate::inspect::inspect_pixel(&s.tracer(), w / 2, h / 3, 0);
    want.set_pixel(&shown, spp);
    assert_eq!(
        (tree.pixel_before_bloom, tree.pixel_after_bloom),
        (want.pixel_before_bloom, want.pixel_after_bloom)
    );
    assert_eq!(tree.color, want.color);
}

#[test]
fn sixteen_colours_are_written_as_ansi_codes() {
    use super::term::screen::Screen;
    use ratatui::layout::Size;
    let req = SceneRequest {
        size: Some((24, 16)),
        ..SceneRequest::new("cornell")
    };
    let (session, warnings) = Session::open(&req).unwrap();
    let mut app = App::new(session, warnings, ColorMode::Ansi16, None).unwrap();
    let mut t = Terminal::new(Screen::new(Vec::new(), Some(Size::new(100, 30))).unwrap()).unwrap();
    app.update(ratatui::layout::Rect::new(0, 0, 100, 30));
    assert!(app.wait_frame(WAIT).unwrap());
    super::draw(&mut t, &mut app).unwrap();
    t.backend_mut().pump(usize::MAX).unwrap();
    let out = String::from_utf8_lossy(t.backend_mut().writer()).into_owned();
    for extended in ["38;5;", "48;5;", "38;2;", "48;2;"] {
        assert!(!out.contains(extended), "{extended} in 16 colours");
    }
    // The viewport's colours: foregrounds 30-37/90-97, backgrounds
    // 40-47/100-107, in the SGR sequences written.
    let codes: Vec<u32> = out
        .split("\x1b[")
        .filter_map(|s| s.split_once('m'))
        .filter(|(p, _)| p.bytes().all(|b| b.is_ascii_digit() || b == b';'))
        .flat_map(|(p, _)| {
            p.split(';')
                .filter_map(|n| n.parse().ok())
                .collect::<Vec<u32>>()
        })
        .collect();
    let has = |r: std::ops::RangeInclusive<u32>| codes.iter().any(|c| r.contains(c));
    assert!(has(30..=37) && has(40..=47) && has(90..=97), "{codes:?}");
    assert!(
        codes
            .iter()
            .all(|&c| c <= 9 || (30..=49).contains(&c) || (90..=107).contains(&c)),
        "{codes:?}"
    );
}

#[test]
fn octants_show_four_times_the_pixels_and_selection_follows() {
    let mut app = app("cornell", &[]);
    app.display.symbols = Symbols::Octant;
    let mut t = terminal(100, 30);
    settle(&mut t, &mut app);
    let v = app.display.layout.image;
    assert_eq!(
        app.display.view_size(),
        (2 * v.width as u32, 4 * v.height as u32)
    );
    // Every cell shows the least-squares fit of its 2x4 pixels.
    let frame = app.link.current_frame().unwrap();
    let b = t.backend().buffer();
    let mut glyphs = std::collections::HashSet::new();
    for cy in 0..v.height {
        for cx in 0..v.width {
            let cell = &b[(v.x + cx, v.y + cy)];
            glyphs.insert(cell.symbol().to_string());
            let shown = symbols::shown_cell(Symbols::Octant, cell.symbol(), cell.fg, cell.bg)
                .unwrap_or_else(|| panic!("{cell:?}"));
            let px: Vec<[f32; 3]> = (0..8)
                .map(|j| {
                    let (x, y) = (2 * cx as u32 + j % 2, 4 * cy as u32 + j / 2);
                    crate::color::srgb(frame.image[(y * frame.width + x) as usize]).map(f32::from)
                })
                .collect();
            let fit = symbols::fit(&px, Symbols::Octant);
            let err: f32 = shown
                .iter()
                .zip(&px)
                .map(|(s, p)| (0..3).map(|c| (s[c] - p[c]).powi(2)).sum::<f32>())
                .sum();
            // The fit's colours, rounded to 8 bits.
            assert!(
                err <= fit.error + 8.0 * 3.0 * 0.25 + 1.0,
                "{cell:?}: {err} vs {}",
                fit.error
            );
        }
    }
    assert!(glyphs.len() > 4, "{glyphs:?}");
    // A click selects the top left pixel of the cell; the mark is drawn.
    let click = ratatui::crossterm::event::Event::Mouse(ratatui::crossterm::event::MouseEvent {
        kind: ratatui::crossterm::event::MouseEventKind::Down(
            ratatui::crossterm::event::MouseButton::Left,
        ),
        column: v.x + 5,
        row: v.y + 3,
        modifiers: ratatui::crossterm::event::KeyModifiers::NONE,
    });
    app.handle_event(&click);
    let s = app.inspector.selected.unwrap();
    assert_eq!((s.x, s.y), (10, 12));
}

#[test]
fn the_render_panel_says_when_the_view_reached_the_screen() {
    use super::term::output::TermOutput;
    use super::term::screen::Screen;
    use ratatui::layout::Size;
    use std::time::Instant;
    let mut app = app("cornell", &[]);
    // Tall enough for the render panel's last line.
    let mut t = Terminal::new(Screen::new(Vec::new(), Some(Size::new(100, 40))).unwrap()).unwrap();
    let mut out = TermOutput::default();
    out.start(t.backend_mut(), Instant::now()).unwrap();
    app.update(ratatui::layout::Rect::new(0, 0, 100, 40));
    assert!(app.wait_frame(WAIT).unwrap());
    super::draw(&mut t, &mut app).unwrap();
    out.drawn(t.backend(), super::shown(&app));
    // Written, and not on screen until the terminal answers.
    out.pump(t.backend_mut(), Instant::now()).unwrap();
    app.note_output(out.figures());
    assert_eq!(app.view_shown_in(), None);
    // The terminal answers each chunk; more is written as answers come.
    while out.waiting() {
        out.answered(Instant::now());
        out.pump(t.backend_mut(), Instant::now()).unwrap();
    }
    app.note_output(out.figures());
    let secs = app.view_shown_in().expect("the full pass is on screen");
    assert!(secs < WAIT.as_secs_f64());
    super::draw(&mut t, &mut app).unwrap();
    let b = t.backend().wanted_text();
    assert!(b.contains("view shown in"), "{b}");
    assert!(b.contains("frames/s"), "{b}");
}

/// Over a link not yet measured (taken as slow), 24-bit colour's first
/// picture of a view goes in 256 colours, and once it is on screen the
/// picture is drawn again in 24-bit colour; the Render panel says both.
#[test]
fn a_slow_link_gets_256_colours_first_then_24_bit() {
    use super::term::output::TermOutput;
    use super::term::screen::Screen;
    use ratatui::layout::Size;
    use std::time::Instant;
    let mut app = app("cornell", &[]);
    assert_eq!(app.display.color, ColorMode::Truecolor);
    let mut t = Terminal::new(Screen::new(Vec::new(), Some(Size::new(120, 40))).unwrap()).unwrap();
    let mut out = TermOutput::default();
    out.start(t.backend_mut(), Instant::now()).unwrap();
    app.update(ratatui::layout::Rect::new(0, 0, 120, 40));
    assert!(app.wait_frame(WAIT).unwrap());
    /// Draws, writes the cells as the terminal answers, and counts the
    /// colours written: (256-colour, 24-bit).
    fn land(
        t: &mut Terminal<Screen<Vec<u8>>>,
        app: &mut App,
        out: &mut TermOutput,
    ) -> (usize, usize) {
        super::draw_frame(t, app, out).unwrap();
        out.pump(t.backend_mut(), Instant::now()).unwrap();
        while out.waiting() {
            out.answered(Instant::now());
            out.pump(t.backend_mut(), Instant::now()).unwrap();
        }
        app.note_output(out.figures());
        let bytes = std::mem::take(t.backend_mut().writer());
        let text = String::from_utf8_lossy(&bytes);
        (text.matches("8;5;").count(), text.matches("8;2;").count())
    }
    let cells = {
        let a = app.display.layout.image;
        a.width as usize * a.height as usize
    };
    // Colours are written where they change: runs of one 256-colour entry
    // take one.
    let (indexed, rgb) = land(&mut t, &mut app, &mut out);
    assert!(app.display.coarse_color);
    assert!(indexed > cells / 4 && rgb < cells / 20, "{indexed} {rgb}");
    assert!(app.view_shown_in().is_some() && app.view_sharp_in().is_none());
    let (indexed, rgb) = land(&mut t, &mut app, &mut out);
    assert!(!app.display.coarse_color);
    assert!(rgb > cells / 2 && indexed < cells / 20, "{indexed} {rgb}");
    assert!(app.view_sharp_in().is_some());
    super::draw(&mut t, &mut app).unwrap();
    let b = t.backend().wanted_text();
    // "view shown in T in 256 colours, 24-bit T", wrapped in the panel.
    assert!(b.contains("view shown in") && b.contains("24-bit"), "{b}");
}

/// The viewport's picture, and the bands that send it all in `mode`.
fn picture_as_bands(
    app: &App,
    mode: &super::graphics::PixelMode,
) -> (super::widgets::viewport::ViewPicture, Vec<Vec<u8>>) {
    use super::graphics::bands::{Bands, Picture};
    let pic = super::widgets::picture(app).unwrap();
    let pieces = Bands::default().update(
        mode,
        &Picture {
            px: &pic.px,
            w: pic.w,
            h: pic.h,
            area: app.display.layout.image,
            coarse: false,
        },
        |_| false,
    );
    (pic, pieces)
}

/// A terminal that draws no sixel image wider than 1000 pixels (xterm's
/// default) gets a picture that narrow, centred in the view, and every
/// band within it.
#[test]
fn the_picture_keeps_within_the_largest_sixel_image() {
    use super::graphics::{sixel, PixelMode, Protocol};
    let mut app = app("cornell", &[]);
    let mode = PixelMode {
        protocol: Protocol::Sixel,
        cell: (7, 14),
        colours: 256,
        passthrough: false,
        pane: None,
        max: Some((1000, 1000)),
    };
    app.display.pixels = Some(mode);
    let mut t = terminal(240, 60);
    settle(&mut t, &mut app);
    let (view, image) = (app.display.layout.view, app.display.layout.image);
    assert_eq!(image.width, 1000 / 7, "{view:?} {image:?}");
    let (left, right) = (image.x - view.x, view.right() - image.right());
    assert!(left.abs_diff(right) <= 1, "{view:?} {image:?}");
    let pieces = picture_as_bands(&app, &mode).1;
    assert!(!pieces.is_empty());
    for p in &pieces {
        let (w, h, _) = sixel::decode(p).unwrap();
        assert!(w <= 1000 && h <= 1000, "{w}x{h}");
    }
}

#[test]
fn kitty_and_sixel_frames_decode_to_the_viewport_picture() {
    use super::graphics::{kitty, sixel, PixelMode, Protocol};
    for protocol in [Protocol::Kitty, Protocol::Sixel] {
        let mut app = app("cornell", &[]);
        let mode = PixelMode {
            protocol,
            cell: (6, 12),
            colours: 256,
            passthrough: false,
            pane: None,
            max: None,
        };
        app.display.pixels = Some(mode);
        let mut t = terminal(100, 30);
        settle(&mut t, &mut app);
        let area = app.display.layout.image;
        // The view is rendered at the cells' pixel size.
        assert_eq!(
            app.display.view_size(),
            (6 * area.width as u32, 12 * area.height as u32)
        );
        // The cells under the picture stay blank for the images.
        let b = t.backend().buffer();
        assert!((area.y..area.y + area.height)
            .all(|y| (area.x..area.x + area.width).all(|x| b[(x, y)].symbol() == " ")));
        // A pixel selected: its mark is part of the picture sent.
        app.select(40, 30, 0);
        let (pic, pieces) = picture_as_bands(&app, &mode);
        assert_eq!(pic.px[(30 * pic.w + 42) as usize], [255, 0, 255]);
        let mut got: Vec<[u8; 3]> = Vec::new();
        for p in &pieces {
            match protocol {
                Protocol::Kitty => got.extend(kitty::decode(p).remove(0).3),
                _ => {
                    let (w, _, px) = sixel::decode(p).unwrap();
                    assert_eq!(w, pic.w as usize);
                    got.extend(px.into_iter().map(|c| c.expect("every pixel set")));
                }
            }
        }
        assert_eq!(got.len(), pic.px.len());
        match protocol {
            // Kitty sends RGB: exactly the picture.
            Protocol::Kitty => assert!(got == pic.px),
            // Sixel: palette colours, dithered: close on average over 4x4
            // blocks, and within the palette's reach per pixel.
            _ => {
                let w = pic.w as usize;
                let mut worst_block = 0f64;
                for by in 0..pic.h as usize / 4 {
                    for bx in 0..w / 4 {
                        let mean = |img: &[[u8; 3]], c: usize| {
                            (0..16)
                                .map(|k| img[(by * 4 + k / 4) * w + bx * 4 + k % 4][c] as f64)
                                .sum::<f64>()
                                / 16.0
                        };
                        for c in 0..3 {
                            worst_block = worst_block.max((mean(&got, c) - mean(&pic.px, c)).abs());
                        }
                    }
                }
                let mean_err = got
                    .iter()
                    .zip(&pic.px)
                    .map(|(a, b)| (0..3).map(|c| a[c].abs_diff(b[c]) as f64).sum::<f64>() / 3.0)
                    .sum::<f64>()
                    / got.len() as f64;
                eprintln!(
                    "sixel: mean error {mean_err:.2}, worst 4x4 block {worst_block:.2} levels"
                );
                assert!(mean_err < 3.0, "{mean_err}");
                assert!(worst_block < 12.0, "{worst_block}");
            }
        }
    }
}

/// The teapot's width over its height on screen, from the second moments
/// of its bright pixels (weighted by how bright, so that the antialiased
/// edge counts in part), each pixel `px` screen pixels in size.
fn teapot_proportions(app: &App, px: (f64, f64)) -> f64 {
    let frame = app.link.current_frame().unwrap();
    let (mut n, mut sx, mut sy, mut sxx, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for y in 0..frame.height {
        for x in 0..frame.width {
            let c = crate::color::srgb(frame.image[(y * frame.width + x) as usize]);
            let l = c.iter().map(|&v| v as f64).sum::<f64>() / 3.0;
            let w = ((l - 165.0) / 30.0).clamp(0.0, 1.0);
            let (fx, fy) = ((x as f64 + 0.5) * px.0, (y as f64 + 0.5) * px.1);
            n += w;
            (sx, sy) = (sx + w * fx, sy + w * fy);
            (sxx, syy) = (sxx + w * fx * fx, syy + w * fy * fy);
        }
    }
    assert!(n > 100.0, "{n} teapot pixels");
    let var = |s: f64, ss: f64| ss / n - (s / n).powi(2);
    (var(sx, sxx) / var(sy, syy)).sqrt()
}

#[test]
fn every_symbol_set_keeps_the_proportions_of_pixel_graphics() {
    use super::graphics::{PixelMode, Protocol};
    // Cells of 7x15 pixels: neither 1:2 nor a whole grid of any symbols.
    let cell = (7, 15);
    let mut measured = Vec::new();
    let modes = [
        Some(Symbols::Half),
        Some(Symbols::Quad),
        Some(Symbols::Sextant),
        Some(Symbols::Octant),
        None,
    ];
    for symbols in modes {
        let mut app = app("teapot", &[]);
        app.display.cell = cell;
        match symbols {
            Some(s) => app.display.symbols = s,
            None => {
                app.display.pixels = Some(PixelMode {
                    protocol: Protocol::Kitty,
                    cell,
                    colours: 256,
                    passthrough: false,
                    pane: None,
                    max: None,
                })
            }
        }
        let mut t = terminal(240, 72);
        settle(&mut t, &mut app);
        // Samples enough for smooth edges.
        while app.link.current_frame().unwrap().spp < 16 {
            app.link.frame = None;
            assert!(app.wait_frame(WAIT).unwrap());
        }
        let (gx, gy) = app.display.layout.grid;
        let px = (cell.0 as f64 / gx as f64, cell.1 as f64 / gy as f64);
        let p = teapot_proportions(&app, px);
        let name = symbols.map_or("pixel graphics", Symbols::name);
        eprintln!("{name}: teapot width/height {p:.3} on screen");
        measured.push((name, p));
    }
    let (_, pixels) = measured[measured.len() - 1];
    for (name, p) in &measured {
        assert!(
            (p / pixels - 1.0).abs() < 0.03,
            "{name}: {p:.3} against {pixels:.3} in pixel graphics"
        );
    }
}

/// Draws, then what was cut, each tagged with `state`.
fn cuts(t: &mut Terminal<TestBackend>, app: &mut App, state: &str) -> Vec<String> {
    super::widgets::fit::take_cut();
    super::draw(t, app).unwrap();
    let (w, h) = (t.size().unwrap().width, t.size().unwrap().height);
    super::widgets::fit::take_cut()
        .into_iter()
        .map(|c| format!("{w}x{h} {state}: {c}"))
        .collect()
}

/// Every panel, overlay legend, popup and message drawn at the smallest,
/// a common and a large size: nothing may be cut.
#[test]
fn nothing_is_cut_from_80x24_to_240x70() {
    let dir = std::env::temp_dir().join(format!("rayterm-tui-cut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut found = Vec::new();
    for (w, h) in [(80, 24), (160, 48), (240, 70)] {
        let mut app = app("cornell-area", &[]);
        app.jobs.export_dir = dir.clone();
        let mut t = terminal(w, h);
        settle(&mut t, &mut app);
        found.extend(cuts(&mut t, &mut app, "first pass"));
        // The last pass: the render panel says it is done (the larger the
        // panel, the more room; the largest view takes long to finish).
        let end = std::time::Instant::now() + WAIT;
        while w < 240
            && !app.current_frame().is_some_and(|f| f.done)
            && std::time::Instant::now() < end
        {
            app.poll().unwrap();
            std::thread::sleep(Duration::from_millis(5));
        }
        found.extend(cuts(&mut t, &mut app, "done"));
        // Each view overlay, then each pixel overlay on a selected pixel.
        for k in 0..crate::viz::image_views(0).len() {
            app.handle_key(Key::Char('g'));
            if app.overlays.image.is_none() {
                break;
            }
            if app
                .overlays
                .image
                .is_some_and(|v| v.source() == crate::viz::DrawnFrom::Film)
            {
                settle_film_view(&mut t, &mut app);
            } else {
                settle(&mut t, &mut app);
            }
            found.extend(cuts(&mut t, &mut app, &format!("view overlay {k}")));
        }
        app.handle_key(Key::Char('v'));
        settle(&mut t, &mut app);
        found.extend(cuts(&mut t, &mut app, "select mode"));
        let (vw, vh) = app.display.view_size();
        app.select(vw / 2, vh * 7 / 8, 0);
        for k in 0..crate::viz::PIXEL_VIEWS.len() {
            app.handle_key(Key::Char('o'));
            if app.overlays.pixel.is_none() {
                break;
            }
            settle_pixel(&mut t, &mut app);
            found.extend(cuts(&mut t, &mut app, &format!("pixel overlay {k}")));
        }
        // Full screen, and the ray-tree pane tall and hidden, with the
        // overlays still on.
        for (key, state) in [
            ('f', "full screen"),
            ('f', "panels"),
            ('T', "tall"),
            ('T', "hidden"),
            ('T', "normal"),
        ] {
            app.handle_key(Key::Char(key));
            settle(&mut t, &mut app);
            found.extend(cuts(&mut t, &mut app, state));
        }
        app.handle_key(Key::Esc);
        // A message, and one beside an export in flight.
        app.handle_key(Key::Char('b'));
        settle(&mut t, &mut app);
        found.extend(cuts(&mut t, &mut app, "builder message"));
        app.handle_key(Key::Char('p'));
        found.extend(cuts(&mut t, &mut app, "export"));
        // Messages said together at start-up, longer than two rows.
        app.say("256 colours: no answer on 24-bit colour, nor COLORTERM; ".repeat(6));
        found.extend(cuts(&mut t, &mut app, "long message"));
        // Every popup.
        for (key, name) in [('?', "help"), ('W', "warnings"), ('x', "stability")] {
            app.handle_key(Key::Char(key));
            let end = std::time::Instant::now() + WAIT;
            while app.popup.is_none() && std::time::Instant::now() < end {
                app.poll().unwrap();
                std::thread::sleep(Duration::from_millis(5));
            }
            app.update(ratatui::layout::Rect::new(0, 0, w, h));
            found.extend(cuts(&mut t, &mut app, name));
            app.handle_key(Key::Esc);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(found.is_empty(), "cut:\n{}", found.join("\n"));
}

#[test]
fn full_screen_and_the_tree_pane_give_the_view_room() {
    let mut app = app("cornell", &[]);
    let mut t = terminal(80, 24);
    settle(&mut t, &mut app);
    let l = app.display.layout;
    let normal = (l.view.width, l.view.height, l.debug.height);
    app.handle_key(Key::Char('f'));
    let s = settle(&mut t, &mut app);
    let l = app.display.layout;
    assert_eq!((l.view.width, l.debug.height), (80, 0), "{s}");
    assert!(!s.contains("Features"), "{s}");
    app.handle_key(Key::Char('f'));
    settle(&mut t, &mut app);
    assert_eq!(app.display.layout.view.width, normal.0);
    // Taller, hidden (its title alone), back.
    app.handle_key(Key::Char('T'));
    settle(&mut t, &mut app);
    assert!(app.display.layout.debug.height > normal.2);
    app.handle_key(Key::Char('T'));
    let s = settle(&mut t, &mut app);
    assert_eq!(app.display.layout.debug.height, 1);
    assert!(s.contains("Ray tree"), "{s}");
    app.handle_key(Key::Char('T'));
    settle(&mut t, &mut app);
    let l = app.display.layout;
    assert_eq!((l.view.width, l.view.height, l.debug.height), normal);
}
