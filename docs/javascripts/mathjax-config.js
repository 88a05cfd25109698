// MathJax 3 settings for pymdownx.arithmatex (generic mode): typeset only the spans it marks.
// MathJax itself (tex-svg-full.js) is copied into the site from the django-static-mathjax package by
// docs/_hooks/mathjax_local.py, so the site renders math offline, without a CDN.
window.MathJax = {
  tex: { inlineMath: [["\\(", "\\)"]], displayMath: [["\\[", "\\]"]], processEscapes: true, processEnvironments: true },
  options: { ignoreHtmlClass: ".*|", processHtmlClass: "arithmatex" },
  svg: { fontCache: "global" },
};
