<script>
(function(){
  function webgl(){try{var c=document.createElement('canvas');
    return !!(window.WebGLRenderingContext&&
      (c.getContext('webgl')||c.getContext('experimental-webgl')));
  }catch(err){return false;}}
  var gl=webgl();
  document.documentElement.setAttribute('data-webgl',gl?'yes':'no');
  document.querySelectorAll('.anim').forEach(function(a){
    if(!gl){a.classList.add('nogl-on');return;}
    var b=a.querySelector('button.play'),t=a.querySelector('template');
    b.addEventListener('click',function(){
      a.appendChild(t.content.cloneNode(true));a.classList.add('playing');b.disabled=true;});
  });
  function reveal(){var id=decodeURIComponent(location.hash.slice(1));if(!id)return;
    var t=document.getElementById(id);if(!t)return;
    for(var p=t.parentElement;p;p=p.parentElement){if(p.tagName==='DETAILS'){p.open=true;}}
    t.scrollIntoView();}
  window.addEventListener('hashchange',reveal);reveal();
})();
</script>
